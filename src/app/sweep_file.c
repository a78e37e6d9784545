/* The sweep file (docs/sweeps.md): its JSON read and checked, every message at the value it
 * is about ("PATH:LINE:COLUMN: key 'grid.cloud.spacing': ..."), the scene given by file name or
 * inline, the grid objects' value lists and ranges, the fixed overrides and the outputs. */
#include "sweep.h"

#include "pstencil.h"
#include "json_pos.h"
#include "scene.h"
#include "text_file.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *text, *path;
    char *err;
    size_t errlen;
} pctx;

/* "PATH:LINE:COL: key 'K': message" at the value that steps[0..depth) leads to. */
static int perr(pctx *c, const json_step *steps, int depth, const char *key, const char *fmt,
                ...) __attribute__((format(printf, 5, 6)));
static int perr(pctx *c, const json_step *steps, int depth, const char *key, const char *fmt,
                ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    int line, col;
    json_pos_find(c->text, steps, depth, &line, &col);
    if (key)
        snprintf(c->err, c->errlen, "%s:%d:%d: key '%s': %s", c->path, line, col, key, msg);
    else
        snprintf(c->err, c->errlen, "%s:%d:%d: %s", c->path, line, col, msg);
    pst_escape_controls(c->err, c->errlen); /* keys may hold any byte */
    return PST_EINPUT;
}

/* Member m of obj when an earlier member has its name: "duplicate key" at this second one
 * (steps[at] is set to it), as the scene loader refuses them. cJSON keeps both, and the
 * lookups would silently take one. */
static int refuse_repeat(pctx *c, const cJSON *obj, const cJSON *m, json_step *steps, int at,
                         const char *full)
{
    int n = 0;
    for (const cJSON *p = obj->child; p != m; p = p->next)
        n += strcmp(p->string, m->string) == 0;
    if (n == 0)
        return PST_OK;
    steps[at] = (json_step){m->string, n};
    return perr(c, steps, at + 1, full, "duplicate key (an earlier '%s' is in the same object)",
                m->string);
}

/* The table path of a dotted override key: list indices become [], a field name <name>. */
static int scene_key_known(const char *key)
{
    char buf[256];
    size_t n = 0;
    const char *p = key, *prev = "";
    char seg[128];
    while (*p) {
        size_t len = strcspn(p, ".");
        if (len == 0 || len >= sizeof seg)
            return 0;
        memcpy(seg, p, len);
        seg[len] = '\0';
        int numeric = strspn(seg, "0123456789") == len;
        const char *add = seg;
        if (numeric) {
            if (n == 0)
                return 0;
            add = "[]";
        } else if (strcmp(prev, "fields") == 0) {
            add = "<name>";
        }
        size_t alen = strlen(add);
        if (n + alen + 2 >= sizeof buf)
            return 0;
        if (n > 0 && !numeric)
            buf[n++] = '.';
        memcpy(buf + n, add, alen);
        n += alen;
        buf[n] = '\0';
        prev = !numeric && strcmp(seg, "fields") == 0 ? "fields" : "";
        p += len;
        if (*p == '.')
            ++p;
    }
    if (n > 2 && strcmp(buf + n - 2, "[]") == 0) /* a whole list item: tasks.1 */
        buf[n - 2] = '\0';
    return n > 0 && sc_param_find(buf) != NULL;
}

/* Line and column (json_pos) back to a byte offset. */
static size_t offset_of(const char *text, int line, int col)
{
    size_t off = 0;
    for (int l = 1; l < line && text[off]; ++off)
        if (text[off] == '\n')
            ++l;
    for (int c = 1; c < col && text[off] && text[off] != '\n'; ++c) {
        ++off;
        while ((text[off] & 0xC0) == 0x80)
            ++off;
    }
    return off;
}

/* The inline scene: the sweep text with everything outside the scene value blanked (newlines
 * kept), so that the scene loader's line:column are the sweep file's. */
static char *inline_scene(pctx *c)
{
    json_step st = {.key = "scene", .index = 0};
    int line, col;
    if (json_pos_find(c->text, &st, 1, &line, &col) != 1)
        return NULL;
    size_t off = offset_of(c->text, line, col);
    const char *p = c->text + off;
    if (*p == '"') { /* skip the member name */
        for (++p; *p && *p != '"'; ++p)
            if (*p == '\\' && p[1])
                ++p;
        if (*p)
            ++p;
    }
    p += strspn(p, " \t\r\n");
    if (*p == ':')
        ++p;
    p += strspn(p, " \t\r\n");
    const char *end = NULL;
    cJSON *v = cJSON_ParseWithOpts(p, &end, 0);
    cJSON_Delete(v);
    if (!v || !end)
        return NULL;
    size_t start = (size_t)(p - c->text), stop = (size_t)(end - c->text);
    char *out = malloc(stop + 1);
    if (!out)
        return NULL;
    for (size_t i = 0; i < stop; ++i)
        out[i] = i >= start ? c->text[i] : (c->text[i] == '\n' ? '\n' : ' ');
    out[stop] = '\0';
    return out;
}

static char *value_text(const cJSON *v)
{
    return cJSON_PrintUnformatted(v);
}


/* Room for n value texts of key k of grid gi. */
static int alloc_values(pst_sweep *sw, int gi, int k, int n)
{
    sw->values[gi][k] = calloc((size_t)n, sizeof(char *));
    if (!sw->values[gi][k])
        return PST_ENOMEM;
    sw->nvalues[gi][k] = n;
    return PST_OK;
}

/* "unknown key (a range is {from, count[, step]}; did you mean 'count'?)" at member m of the
 * range object at steps[0..depth). */
static int unknown_range_member(pctx *c, json_step *steps, int depth, const char *full,
                                const cJSON *m)
{
    static const char *const members[] = {"from", "count", "step"};
    const char *best = sc_suggest_word(m->string, members, 3);
    char sub[340], hint[64] = "";
    snprintf(sub, sizeof sub, "%s.%s", full, m->string);
    if (best)
        snprintf(hint, sizeof hint, "; did you mean '%s'?", best);
    steps[depth] = (json_step){m->string, 0};
    return perr(c, steps, depth + 1, sub, "unknown key (a range is {from, count[, step]}%s)",
                hint);
}

/* A range {from, count[, step]}: count numbers from `from`, `step` apart (default 1). steps
 * has room for one more step past depth (a member's). */
static int read_range(pctx *c, json_step *steps, int depth, const char *full,
                      const cJSON *item, pst_sweep *sw, int gi, int k)
{
    const cJSON *from = cJSON_GetObjectItemCaseSensitive(item, "from"),
                *count = cJSON_GetObjectItemCaseSensitive(item, "count"),
                *step = cJSON_GetObjectItemCaseSensitive(item, "step"), *m;
    cJSON_ArrayForEach(m, item)
    {
        if (strcmp(m->string, "from") && strcmp(m->string, "count") && strcmp(m->string, "step"))
            return unknown_range_member(c, steps, depth, full, m);
        char sub[340];
        snprintf(sub, sizeof sub, "%s.%s", full, m->string);
        if (refuse_repeat(c, item, m, steps, depth, sub) != PST_OK)
            return PST_EINPUT;
    }
    if (!cJSON_IsNumber(from) || !cJSON_IsNumber(count) || count->valuedouble < 1 ||
        count->valuedouble > 1e6 || count->valuedouble != floor(count->valuedouble) ||
        (step && !cJSON_IsNumber(step)))
        return perr(c, steps, depth, full, "a range needs a number 'from' and a whole 'count' "
                                           ">= 1 (and a number 'step')");
    int n = (int)count->valuedouble;
    double s = step ? step->valuedouble : 1;
    if (alloc_values(sw, gi, k, n) != PST_OK)
        return PST_ENOMEM;
    for (int v = 0; v < n; ++v) {
        cJSON *num = cJSON_CreateNumber(from->valuedouble + s * v);
        sw->values[gi][k][v] = num ? value_text(num) : NULL;
        cJSON_Delete(num);
        if (!sw->values[gi][k][v])
            return PST_ENOMEM;
    }
    return PST_OK;
}

/* The values of key k of grid gi: a list of JSON values or a range. */
static int read_values(pctx *c, json_step *steps, int depth, const char *full,
                       const cJSON *item, pst_sweep *sw, int gi, int k)
{
    if (cJSON_IsObject(item))
        return read_range(c, steps, depth, full, item, sw, gi, k);
    if (!cJSON_IsArray(item))
        return perr(c, steps, depth, full, "expected a list of values or a range "
                                           "{\"from\": A, \"count\": N}");
    int n = cJSON_GetArraySize(item);
    if (n == 0)
        return perr(c, steps, depth, full, "empty list of values");
    if (alloc_values(sw, gi, k, n) != PST_OK)
        return PST_ENOMEM;
    for (int v = 0; v < n; ++v)
        if (!(sw->values[gi][k][v] = value_text(cJSON_GetArrayItem(item, v))))
            return PST_ENOMEM;
    return PST_OK;
}

/* Grid key k of grid gi: a known scene key, the first grid's k-th key in the others (a key
 * repeated in one object is refused before). */
static int read_key(pctx *c, json_step *steps, int depth, const char *full, const char *key,
                    pst_sweep *sw, int gi, int k)
{
    if (k >= SW_MAX_KEYS)
        return perr(c, steps, depth, full, "more than %d grid keys", SW_MAX_KEYS);
    if (!scene_key_known(key))
        return perr(c, steps, depth, full, "unknown scene key (pstencil help scene lists "
                                           "them; list items are numbered from 0)");
    if (gi > 0 && (k >= sw->nkeys || strcmp(sw->keys[k], key) != 0))
        return perr(c, steps, depth, full, "every grid object must have the keys of the "
                                           "first, in the same order");
    if (gi == 0) {
        if (!(sw->keys[k] = pst_strdup(key)))
            return PST_ENOMEM;
        sw->nkeys = k + 1;
    }
    return PST_OK;
}

/* One grid object: keys and their value lists. steps: "grid", the list item, the key and a
 * range's member. */
static int read_grid(pctx *c, const cJSON *g, int gi, int listed, pst_sweep *sw)
{
    json_step steps[4] = {{"grid", 0}, {NULL, gi}, {NULL, 0}, {NULL, 0}};
    int d0 = listed ? 2 : 1;
    if (!cJSON_IsObject(g))
        return perr(c, steps, d0, "grid", "expected an object of key: [values]");
    int k = 0;
    const cJSON *item;
    cJSON_ArrayForEach(item, g)
    {
        steps[d0] = (json_step){item->string, 0};
        char full[300];
        snprintf(full, sizeof full, "grid.%s", item->string);
        int st = refuse_repeat(c, g, item, steps, d0, full);
        if (st == PST_OK)
            st = read_key(c, steps, d0 + 1, full, item->string, sw, gi, k);
        if (st == PST_OK)
            st = read_values(c, steps, d0 + 1, full, item, sw, gi, k);
        if (st != PST_OK)
            return st;
        ++k;
    }
    if (k == 0)
        return perr(c, steps, d0, "grid", "no keys");
    if (gi > 0 && k != sw->nkeys)
        return perr(c, steps, d0, "grid", "every grid object must have the keys of the first");
    return PST_OK;
}

/* "scene": a file name (relative to the sweep file's folder) or an inline object. */
static int read_scene(pctx *c, const cJSON *root, pst_sweep *sw)
{
    const cJSON *scene = cJSON_GetObjectItemCaseSensitive(root, "scene");
    json_step steps[1] = {{"scene", 0}};
    if (cJSON_IsObject(scene)) {
        sw->scene_path = pst_strdup(c->path);
        sw->scene_text = inline_scene(c);
        return sw->scene_path && sw->scene_text ? PST_OK : PST_ENOMEM;
    }
    if (!cJSON_IsString(scene))
        return perr(c, steps, scene ? 1 : 0, "scene",
                    scene ? "expected a scene file name or a scene object" : "required");
    const char *file = scene->valuestring;
    const char *slash = strrchr(c->path, '/');
    size_t dl = slash && file[0] != '/' ? (size_t)(slash - c->path) + 1 : 0;
    sw->scene_path = malloc(dl + strlen(file) + 1);
    if (!sw->scene_path)
        return PST_ENOMEM;
    memcpy(sw->scene_path, c->path, dl);
    strcpy(sw->scene_path + dl, file);
    char msg[PST_ERRLEN + 512];
    int st = PST_OK;
    sw->scene_text = pst_read_text(sw->scene_path, NULL, msg, sizeof msg, &st);
    if (!sw->scene_text)
        perr(c, steps, 1, "scene", "%s", msg);
    return st;
}

/* "grid": one object or a list of them; ncombos, the runs of their union. */
static int read_grids(pctx *c, const cJSON *root, pst_sweep *sw)
{
    const cJSON *grid = cJSON_GetObjectItemCaseSensitive(root, "grid");
    json_step steps[1] = {{"grid", 0}};
    if (!grid)
        return perr(c, steps, 0, "grid", "required");
    int listed = cJSON_IsArray(grid), n = listed ? cJSON_GetArraySize(grid) : 1;
    if (listed && (n == 0 || n > SW_MAX_GRIDS))
        return perr(c, steps, 1, "grid", "a list of 1 to %d grid objects", SW_MAX_GRIDS);
    for (int g = 0; g < n; ++g) {
        int st = read_grid(c, listed ? cJSON_GetArrayItem(grid, g) : grid, g, listed, sw);
        if (st != PST_OK)
            return st;
        sw->ngrids = g + 1;
    }
    /* counted in double (exact up to 2^53, never wrapping) against the cap */
    double total = 0;
    for (int g = 0; g < sw->ngrids; ++g) {
        double p = 1;
        for (int k = 0; k < sw->nkeys; ++k)
            p *= sw->nvalues[g][k];
        total += p;
    }
    if (total > SW_MAX_COMBOS)
        return perr(c, steps, 1, "grid", "%.15g combinations, more than the %d a sweep may have",
                    total, SW_MAX_COMBOS);
    sw->ncombos = (size_t)total;
    return PST_OK;
}

/* "overrides": fixed "key=json" scene overrides, none of them a grid key. */
static int read_overrides(pctx *c, const cJSON *root, pst_sweep *sw)
{
    const cJSON *ov = cJSON_GetObjectItemCaseSensitive(root, "overrides"), *m;
    json_step steps[2] = {{"overrides", 0}, {NULL, 0}};
    if (ov && !cJSON_IsObject(ov))
        return perr(c, steps, 1, "overrides", "expected an object of key: value");
    cJSON_ArrayForEach(m, ov)
    {
        char full[300];
        snprintf(full, sizeof full, "overrides.%s", m->string);
        steps[1] = (json_step){m->string, 0};
        if (sw->noverrides >= SW_MAX_OVERRIDES)
            return perr(c, steps, 2, full, "more than %d overrides", SW_MAX_OVERRIDES);
        if (!scene_key_known(m->string))
            return perr(c, steps, 2, full, "unknown scene key");
        if (refuse_repeat(c, ov, m, steps, 1, full) != PST_OK)
            return PST_EINPUT;
        for (int k = 0; k < sw->nkeys; ++k)
            if (strcmp(sw->keys[k], m->string) == 0)
                return perr(c, steps, 2, full, "also a grid key");
        char *vt = value_text(m);
        if (!vt)
            return PST_ENOMEM;
        size_t n = strlen(m->string) + strlen(vt) + 2;
        char *o = malloc(n);
        if (o)
            snprintf(o, n, "%s=%s", m->string, vt);
        free(vt);
        if (!o)
            return PST_ENOMEM;
        sw->overrides[sw->noverrides++] = o;
    }
    return PST_OK;
}

/* A default output: the sweep file's stem with `suffix`, in the working directory. */
static int default_output(const char *path, const char *suffix, char **dst)
{
    if (*dst)
        return PST_OK;
    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    const char *dot = strrchr(base, '.');
    int stem = dot ? (int)(dot - base) : (int)strlen(base);
    char name[512];
    snprintf(name, sizeof name, "%.*s%s", stem, base, suffix);
    return (*dst = pst_strdup(name)) ? PST_OK : PST_ENOMEM;
}

/* "output": {csv, summary, pvd} file names (pvd optional, a .pvd). */
static int read_outputs(pctx *c, const cJSON *root, pst_sweep *sw)
{
    const cJSON *out = cJSON_GetObjectItemCaseSensitive(root, "output"), *m;
    json_step steps[2] = {{"output", 0}, {NULL, 0}};
    if (out && !cJSON_IsObject(out))
        return perr(c, steps, 1, "output", "expected an object {csv, summary, pvd}");
    cJSON_ArrayForEach(m, out)
    {
        steps[1] = (json_step){m->string, 0};
        char full[300];
        snprintf(full, sizeof full, "output.%s", m->string);
        char **dst = strcmp(m->string, "csv") == 0       ? &sw->csv
                     : strcmp(m->string, "summary") == 0 ? &sw->summary
                     : strcmp(m->string, "pvd") == 0     ? &sw->pvd
                                                         : NULL;
        if (!dst)
            return perr(c, steps, 2, full, "unknown key (output has csv, summary and pvd)");
        if (refuse_repeat(c, out, m, steps, 1, full) != PST_OK)
            return PST_EINPUT;
        if (!cJSON_IsString(m) || !m->valuestring[0])
            return perr(c, steps, 2, full, "expected a file name");
        size_t len = strlen(m->valuestring);
        if (dst == &sw->pvd && (len < 5 || strcmp(m->valuestring + len - 4, ".pvd") != 0))
            return perr(c, steps, 2, full, "expected a file name ending in .pvd");
        if (!(*dst = pst_strdup(m->valuestring)))
            return PST_ENOMEM;
    }
    if (default_output(c->path, ".csv", &sw->csv) != PST_OK)
        return PST_ENOMEM;
    return default_output(c->path, ".summary.json", &sw->summary);
}

/* "slope_key" and "repeat_key": two different scene keys (defaults cloud.spacing, cloud.seed). */
static int read_stat_keys(pctx *c, const cJSON *root, pst_sweep *sw)
{
    const char *names[2] = {"slope_key", "repeat_key"}, *defs[2] = {"cloud.spacing", "cloud.seed"};
    char **dsts[2] = {&sw->slope_key, &sw->repeat_key};
    json_step steps[1];
    for (int q = 0; q < 2; ++q) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, names[q]);
        steps[0] = (json_step){names[q], 0};
        if (v && (!cJSON_IsString(v) || !scene_key_known(v->valuestring)))
            return perr(c, steps, 1, names[q], "expected a scene key");
        if (!(*dsts[q] = pst_strdup(v ? v->valuestring : defs[q])))
            return PST_ENOMEM;
    }
    if (strcmp(sw->slope_key, sw->repeat_key) == 0)
        return perr(c, steps, 1, "repeat_key", "the same key as slope_key");
    return PST_OK;
}

static int read_sweep(pctx *c, const cJSON *root, pst_sweep *sw)
{
    json_step steps[1] = {{NULL, 0}};
    if (!cJSON_IsObject(root))
        return perr(c, steps, 0, NULL, "expected a JSON object");
    static const char *const known[] = {"scene", "grid", "overrides", "output", "slope_key",
                                        "repeat_key", "title"};
    const cJSON *m;
    cJSON_ArrayForEach(m, root)
    {
        int ok = 0;
        for (size_t q = 0; q < sizeof known / sizeof known[0]; ++q)
            ok |= strcmp(m->string, known[q]) == 0;
        steps[0] = (json_step){m->string, 0};
        if (!ok)
            return perr(c, steps, 1, m->string, "unknown key (a sweep has scene, grid, "
                                                "overrides, output, slope_key, repeat_key, "
                                                "title)");
        if (refuse_repeat(c, root, m, steps, 0, m->string) != PST_OK)
            return PST_EINPUT;
    }
    int (*const parts[])(pctx *, const cJSON *, pst_sweep *) = {
        read_scene, read_grids, read_overrides, read_outputs, read_stat_keys};
    for (size_t q = 0; q < sizeof parts / sizeof parts[0]; ++q) {
        int st = parts[q](c, root, sw);
        if (st != PST_OK)
            return st;
    }
    return PST_OK;
}

void pst_sweep_free(pst_sweep *sw)
{
    if (!sw)
        return;
    free(sw->path);
    free(sw->scene_text);
    free(sw->scene_path);
    for (int g = 0; g < SW_MAX_GRIDS; ++g)
        for (int k = 0; k < SW_MAX_KEYS; ++k) {
            for (int v = 0; v < sw->nvalues[g][k]; ++v)
                free(sw->values[g][k][v]);
            free(sw->values[g][k]);
        }
    for (int k = 0; k < sw->nkeys; ++k)
        free(sw->keys[k]);
    for (int q = 0; q < sw->noverrides; ++q)
        free(sw->overrides[q]);
    free(sw->csv);
    free(sw->summary);
    free(sw->pvd);
    free(sw->slope_key);
    free(sw->repeat_key);
    memset(sw, 0, sizeof *sw);
}


int pst_sweep_parse(pst_sweep *sw, const char *text, const char *path, char *err,
                    size_t errlen)
{
    memset(sw, 0, sizeof *sw);
    err[0] = '\0';
    pctx c = {.text = text, .path = path, .err = err, .errlen = errlen};
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    if (!root) {
        int line, col;
        json_pos_error(text, end, &line, &col);
        if (json_pos_too_deep(text, end))
            snprintf(err, errlen, "%s:%d:%d: JSON nested deeper than %d levels", path, line, col,
                     CJSON_NESTING_LIMIT);
        else
            snprintf(err, errlen, "%s:%d:%d: JSON syntax error", path, line, col);
        return PST_EINPUT;
    }
    sw->path = pst_strdup(path);
    int st = sw->path ? read_sweep(&c, root, sw) : PST_ENOMEM;
    cJSON_Delete(root);
    if (st == PST_OK) { /* the scene must parse with the fixed overrides */
        const char *ov[SW_MAX_OVERRIDES + 1];
        ov[0] = "outputs={}";
        for (int q = 0; q < sw->noverrides; ++q)
            ov[q + 1] = sw->overrides[q];
        pst_scene s;
        char msg[PST_ERRLEN * 2];
        st = pst_scene_parse(&s, sw->scene_text, sw->scene_path, ov, sw->noverrides + 1, msg,
                             sizeof msg);
        if (st == PST_OK)
            pst_scene_free(&s);
        else
            snprintf(err, errlen, "%s: the scene: %s", path, msg);
    }
    if (st == PST_ENOMEM && !err[0])
        snprintf(err, errlen, "%s: out of memory", path);
    if (st != PST_OK)
        pst_sweep_free(sw);
    return st;
}

int pst_sweep_load(pst_sweep *sw, const char *path, char *err, size_t errlen)
{
    memset(sw, 0, sizeof *sw);
    int st = PST_OK;
    char *text = pst_read_text(path, NULL, err, errlen, &st);
    if (!text)
        return st;
    st = pst_sweep_parse(sw, text, path, err, errlen);
    free(text);
    return st;
}
