/* Two outputs of a scene (csv, vtu, report) on one file would overwrite each other: refuse the
 * scene, naming both keys. Paths are compared after normalisation: the folder by its real path
 * when it exists ("./a/../x.csv" and "x.csv" are one file), else the text with "." segments and
 * repeated slashes removed. */
#define _XOPEN_SOURCE 700 /* realpath */

#include "scene_walk.h"

#include "pstencil.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* `path` without "./" segments and repeated slashes, in out. */
static void tidy(const char *path, char *out, size_t len)
{
    size_t n = 0;
    for (const char *p = path; *p && n + 1 < len;) {
        if (p[0] == '/' && (n > 0 ? out[n - 1] == '/' : p != path)) {
            ++p;
        } else if (p[0] == '.' && p[1] == '/' && (p == path || p[-1] == '/')) {
            p += 2;
        } else {
            out[n++] = *p++;
        }
    }
    out[n] = '\0';
}

/* The normal form of an output path in out (PATH_MAX bytes). */
static void normalise(const char *path, char *out)
{
    char t[PATH_MAX], dir[PATH_MAX];
    tidy(path, t, sizeof t);
    const char *slash = strrchr(t, '/');
    const char *base = slash ? slash + 1 : t;
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else
        snprintf(dir, sizeof dir, "%.*s", slash == t ? 1 : (int)(slash - t), t);
    char real[PATH_MAX];
    size_t rn = realpath(dir, real) ? strlen(real) : 0, bn = strlen(base);
    if (rn > 0 && rn + bn + 2 <= PATH_MAX) {
        if (strcmp(real, "/") == 0)
            rn = 0;
        memcpy(out, real, rn);
        out[rn] = '/';
        memcpy(out + rn + 1, base, bn + 1);
    } else {
        memcpy(out, t, strlen(t) + 1);
    }
}

int scene_check_output_paths(ctx *c, const pst_scene *s)
{
    const char *keys[3] = {"csv", "vtu", "report"};
    const char *paths[3] = {s->out.csv, s->out.vtu, s->out.report};
    char norm[3][PATH_MAX];
    for (int a = 0; a < 3; ++a) {
        if (paths[a])
            normalise(paths[a], norm[a]);
        for (int b = 0; b < a && paths[a]; ++b)
            if (paths[b] && strcmp(norm[a], norm[b]) == 0)
                return scene_error(c, keys[a], "outputs.%s and outputs.%s are the same file "
                                   "'%s': one would overwrite the other", keys[b], keys[a],
                                   paths[a]);
    }
    return PST_OK;
}
