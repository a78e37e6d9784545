/* The grid of a sweep: combination k's key values (grid after grid, the last key fastest),
 * its label and its scene, and the --plan check of every combination. */
#include "sweep_grid.h"

#include "pstencil.h"
#include "plan.h"
#include "text_file.h"

#include <cjson/cJSON.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void pst_sweep_combo(const pst_sweep *sw, size_t k, const char *vals[SW_MAX_KEYS])
{
    int g = 0;
    for (; g < sw->ngrids; ++g) {
        size_t p = 1;
        for (int q = 0; q < sw->nkeys; ++q)
            p *= (size_t)sw->nvalues[g][q];
        if (k < p)
            break;
        k -= p;
    }
    if (g == sw->ngrids)
        g = sw->ngrids - 1;
    for (int q = sw->nkeys - 1; q >= 0; --q) { /* the last key fastest */
        size_t n = (size_t)sw->nvalues[g][q];
        vals[q] = sw->values[g][q][k % n];
        k /= n;
    }
}

void sweep_combo_label(const pst_sweep *sw, size_t k, char *buf, size_t len)
{
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(sw, k, vals);
    size_t n = 0;
    buf[0] = '\0';
    for (int q = 0; q < sw->nkeys && n < len; ++q)
        n += (size_t)snprintf(buf + n, len - n, "%s%s=%s", q ? " " : "", sw->keys[q], vals[q]);
}

void sweep_run_vtu(const pst_sweep *sw, size_t k, char *path, size_t len, const char **base)
{
    int stem = (int)strlen(sw->pvd) - 4; /* the sweep file's check: it ends in .pvd */
    snprintf(path, len, "%.*s_run%zu.vtu", stem, sw->pvd, k);
    if (base) {
        const char *slash = strrchr(path, '/');
        *base = slash ? slash + 1 : path;
    }
}

static uint64_t fnv(uint64_t h, const char *s)
{
    for (; s && *s; ++s)
        h = (h ^ (unsigned char)*s) * 0x100000001b3ULL;
    return (h ^ 0xff) * 0x100000001b3ULL; /* a separator: ("ab", "c") is not ("a", "bc") */
}

uint64_t sweep_digest(const pst_sweep *sw)
{
    uint64_t h = 0xcbf29ce484222325ULL;
    h = fnv(fnv(fnv(fnv(h, sw->scene_text), sw->scene_path), sw->csv), sw->pvd);
    for (int q = 0; q < sw->noverrides; ++q)
        h = fnv(h, sw->overrides[q]);
    for (int g = 0; g < sw->ngrids; ++g)
        for (int q = 0; q < sw->nkeys; ++q) {
            h = fnv(h, sw->keys[q]);
            for (int v = 0; v < sw->nvalues[g][q]; ++v)
                h = fnv(h, sw->values[g][q][v]);
        }
    return h;
}

/* "outputs=..." of run k: none, or only its VTU when the sweep collects them in a .pvd. */
static char *outputs_override(const pst_sweep *sw, size_t k)
{
    if (!sw->pvd)
        return pst_strdup("outputs={}");
    char path[1024];
    sweep_run_vtu(sw, k, path, sizeof path, NULL);
    cJSON *o = cJSON_CreateObject();
    char *json = o && cJSON_AddStringToObject(o, "vtu", path) ? cJSON_PrintUnformatted(o) : NULL;
    cJSON_Delete(o);
    size_t len = json ? strlen(json) + 9 : 0;
    char *ov = json ? malloc(len) : NULL;
    if (ov)
        snprintf(ov, len, "outputs=%s", json);
    free(json);
    return ov;
}

/* Overrides of one run: outputs off (or its VTU), the fixed ones, then the grid's. */
static int run_overrides(const pst_sweep *sw, size_t k, char **ov, int *nov)
{
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(sw, k, vals);
    int n = 0;
    ov[n++] = outputs_override(sw, k);
    for (int q = 0; q < sw->noverrides; ++q)
        ov[n++] = pst_strdup(sw->overrides[q]);
    for (int q = 0; q < sw->nkeys; ++q) {
        size_t len = strlen(sw->keys[q]) + strlen(vals[q]) + 2;
        ov[n] = malloc(len);
        if (ov[n])
            snprintf(ov[n], len, "%s=%s", sw->keys[q], vals[q]);
        ++n;
    }
    *nov = n;
    for (int q = 0; q < n; ++q)
        if (!ov[q])
            return PST_ENOMEM;
    return PST_OK;
}

int sweep_combo_scene(const pst_sweep *sw, size_t k, pst_scene *s, char *msg, size_t msglen)
{
    char *ov[SW_MAX_OVERRIDES + SW_MAX_KEYS + 1];
    int nov = 0;
    int st = run_overrides(sw, k, ov, &nov);
    if (st == PST_OK)
        st = pst_scene_parse(s, sw->scene_text, sw->scene_path, (const char *const *)ov, nov,
                             msg, msglen);
    else
        snprintf(msg, msglen, "out of memory");
    for (int q = 0; q < nov; ++q)
        free(ov[q]);
    return st;
}

int pst_sweep_check(const pst_sweep *sw, size_t *nfailed, char *err, size_t errlen)
{
    int first = PST_OK;
    size_t bad = 0;
    err[0] = '\0';
    for (size_t k = 0; k < sw->ncombos; ++k) {
        pst_scene s;
        char msg[PST_ERRLEN * 2];
        int st = sweep_combo_scene(sw, k, &s, msg, sizeof msg);
        if (st == PST_OK) {
            pst_plan p;
            st = pst_plan_make(&p, &s, pst_plan_particles(&s), NULL, msg, sizeof msg);
            pst_scene_free(&s);
        }
        if (st != PST_OK) {
            if (first == PST_OK) {
                char label[512];
                sweep_combo_label(sw, k, label, sizeof label);
                snprintf(err, errlen, "combination %zu (%s): %s", k, label, msg);
                first = st;
            }
            ++bad;
        }
    }
    if (nfailed)
        *nfailed = bad;
    return first;
}
