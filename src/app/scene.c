/* Scene loading: JSON text (cJSON) -> overrides -> a check of every key against the parameter
 * table (scene_params.c) -> a pst_scene with every default filled in -> the checks that
 * involve several keys. Errors name the key and its line:column in the text (json_pos.c), or
 * the override that produced the key. The walk keeps the path from the root as a stack of
 * steps, so that any check can report where it is. */
#include "scene_walk.h"

#include "pstencil.h"
#include "scene_default_json.h"
#include "text_file.h"

#include <cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* "JSON syntax error near 'xyz'" with the text at the error, or the end of the text. */
static int syntax_error(ctx *c, const char *at)
{
    int line, col;
    size_t len = strlen(c->text);
    size_t off = at && at >= c->text && at <= c->text + len ? (size_t)(at - c->text) : len;
    /* cJSON reports a member name that is not a string one byte late: "{..., }" points past
     * the '}' */
    if (off > 0 && off <= len && c->text[off - 1] == '}' && at) {
        --off;
        --at;
    }
    json_pos_error(c->text, at, &line, &col);
    if (!c->err || c->errlen == 0)
        return PST_EINPUT;
    if (c->text[strspn(c->text, " \t\r\n")] == '\0') {
        snprintf(c->err, c->errlen, "%s:%d:%d: empty file (expected a JSON object)", c->path,
                 line, col);
    } else if (json_pos_too_deep(c->text, c->text + off)) {
        snprintf(c->err, c->errlen, "%s:%d:%d: JSON nested deeper than %d levels", c->path, line,
                 col, CJSON_NESTING_LIMIT);
    } else if (off >= len) {
        snprintf(c->err, c->errlen, "%s:%d:%d: JSON syntax error: unexpected end of the text",
                 c->path, line, col);
    } else {
        char near[24];
        size_t n = 0;
        for (const char *p = c->text + off; *p && *p != '\n' && n < sizeof near - 1; ++p)
            near[n++] = (*p >= 32 && *p < 127) ? *p : '?';
        near[n] = '\0';
        snprintf(c->err, c->errlen, "%s:%d:%d: JSON syntax error near '%s'", c->path, line, col,
                 near);
    }
    return PST_EINPUT;
}

static int read_scene(ctx *c, cJSON *root, pst_scene *s, int noverrides)
{
    if (!cJSON_IsObject(root))
        return scene_error(c, NULL, "a scene must be a JSON object, got %s", scene_json_kind(root));
    for (int k = 0; k < noverrides; ++k) {
        int rc = scene_apply_override(c, root, k);
        if (rc != PST_OK)
            return rc;
    }
    c->dim = 2;
    const cJSON *dim = scene_member(root, "dim");
    if (dim) { /* every vector's length depends on it: check it first */
        scene_push_member(c, dim);
        int rc = scene_check_value(c, dim, sc_param_find("dim"), SC_T_INT);
        scene_pop(c);
        if (rc != PST_OK)
            return rc;
        c->dim = (int)dim->valuedouble;
    }
    int rc = scene_check_object(c, root, NULL, "");
    if (rc != PST_OK)
        return rc;
    s->dim = c->dim;
    const char *title = scene_get_string(root, "title");
    if ((rc = scene_set_str(c, &s->title, title ? title : s->path)) != PST_OK ||
        (rc = scene_read_cloud(c, root, s)) != PST_OK ||
        (rc = scene_read_mobility(c, root, s)) != PST_OK ||
        (rc = scene_read_operator(c, root, s)) != PST_OK ||
        (rc = scene_read_fields(c, root, s)) != PST_OK ||
        (rc = scene_read_tasks(c, root, s)) != PST_OK ||
        (rc = scene_read_outputs(c, root, s)) != PST_OK)
        return rc;
    s->memory_fraction = scene_get_real(scene_member(root, "limits"), "limits.memory_fraction");
    return PST_OK;
}

/* The folder of a file name: "." without a slash. */
static char *folder_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        return pst_strdup(".");
    size_t n = slash == path ? 1 : (size_t)(slash - path);
    char *d = malloc(n + 1);
    if (d) {
        memcpy(d, path, n);
        d[n] = '\0';
    }
    return d;
}

int pst_scene_parse(pst_scene *s, const char *text, const char *path, const char *const *overrides,
                    int noverrides, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    if (err && errlen)
        err[0] = '\0';
    if (!text || !path || noverrides < 0 || (noverrides > 0 && !overrides)) {
        if (err && errlen)
            snprintf(err, errlen, "pst_scene_parse: bad arguments");
        return PST_EINVAL;
    }
    ctx c = {.text = text, .path = path, .err = err, .errlen = errlen, .dim = 2,
             .overrides = overrides};
    s->path = pst_strdup(path);
    s->dir = folder_of(path);
    if (!s->path || !s->dir) {
        pst_scene_free(s);
        return PST_ENOMEM;
    }
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    int rc = root ? read_scene(&c, root, s, noverrides) : syntax_error(&c, end);
    cJSON_Delete(root);
    free(c.marks);
    if (c.status != PST_OK)
        rc = c.status;
    if (rc == PST_ENOMEM && err && errlen)
        snprintf(err, errlen, "%s: out of memory", path);
    if (rc != PST_OK)
        pst_scene_free(s);
    return rc;
}

int pst_scene_load(pst_scene *s, const char *path, const char *const *overrides, int noverrides,
                   char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    size_t len;
    int rc = PST_OK;
    char *text = pst_read_text(path, &len, err, errlen, &rc);
    if (!text)
        return rc;
    if (strlen(text) != len) { /* the parser would stop at the NUL and misreport */
        int line, col;
        json_pos_offset(text, strlen(text), &line, &col);
        if (err && errlen)
            snprintf(err, errlen, "%s:%d:%d: a NUL byte in the file", path, line, col);
        rc = PST_EINPUT;
    } else {
        rc = pst_scene_parse(s, text, path, overrides, noverrides, err, errlen);
    }
    free(text);
    return rc;
}

int pst_scene_default(pst_scene *s, const char *const *overrides, int noverrides, char *err,
                      size_t errlen)
{
    return pst_scene_parse(s, pst_scene_default_json, "(built-in)", overrides, noverrides, err,
                           errlen);
}

void pst_scene_free(pst_scene *s)
{
    if (!s)
        return;
    free(s->path);
    free(s->dir);
    free(s->title);
    free(s->cloud.file);
    for (int k = 0; k < 3; ++k)
        free(s->mobility.expr[k]);
    free(s->mobility.file);
    free(s->op.scheme);
    for (int k = 0; k < s->nfields; ++k) {
        free(s->fields[k].name);
        free(s->fields[k].expr);
    }
    for (int i = 0; i < s->ntasks; ++i) {
        sc_task *t = &s->tasks[i];
        free(t->name);
        free(t->field);
        for (int k = 0; k < 6; ++k)
            free(t->exact[k]);
        free(t->points_file);
        free(t->rhs);
        free(t->petsc);
        free(t->initial);
        free(t->source);
        free(t->boundary_value);
        for (int k = 0; k < 3; ++k)
            free(t->velocity[k]);
        free(t->pvd);
        free(t->steps_csv);
        for (int g = 0; g < t->ngroups; ++g) {
            free(t->groups[g].value);
            free(t->groups[g].region.expr);
        }
    }
    free(s->out.csv);
    free(s->out.vtu);
    free(s->out.report);
    for (int k = 0; k < s->out.nfields; ++k)
        free(s->out.fields[k]);
    memset(s, 0, sizeof *s);
}
