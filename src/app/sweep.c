/* Sweeps (docs/sweeps.md): the sweep file, the runs, the CSV (rewritten all or nothing after
 * every run, so an interrupted sweep loses at most the run in progress), --resume and the
 * summary, which is computed from the CSV's cells only so that it can be recomputed from the
 * file. */
#include "sweep.h"

#include "pstencil.h"
#include "json_pos.h"
#include "plan.h"
#include "progress.h"
#include "report.h"
#include "run.h"
#include "scene.h"
#include "text_file.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

const char *const pst_sweep_columns[] = {
    "dim", "particles", "neighbours_estimate", "task", "type", "rel_l2", "qsfdi11",
    "qsfdi11_normalised", "lv78", "lv95", "max_abs", "max_rel", "iterations", "converged",
    "rel_residual", "t_cloud", "t_neighbours", "t_geometry", "t_moments", "t_inversion",
    "t_weights", "t_precompute", "t_task", "t_total", "cpu", "peak_rss_bytes", "memory_estimate",
    "rows_ok", "rows_fallback", "rows_ill_conditioned", "rows_rank_deficient", "rows_too_few",
    "status", "message"};
const int pst_sweep_ncolumns = (int)(sizeof pst_sweep_columns / sizeof pst_sweep_columns[0]);

enum { C_DIM, C_PARTICLES, C_NEIGH, C_TASK, C_TYPE, C_NORM0, C_ITER = C_NORM0 + 7, C_CONV,
       C_RESID, C_T_CLOUD, C_T_NEIGH, C_T_GEOM, C_T_MOM, C_T_INV, C_T_W, C_T_PRE, C_T_TASK,
       C_T_TOTAL, C_CPU, C_RSS, C_MEM, C_ROWS0, C_STATUS = C_ROWS0 + 5, C_MESSAGE, C_N };

static const char *const norm_cols[7] = {"rel_l2", "qsfdi11", "qsfdi11_normalised", "lv78",
                                         "lv95",   "max_abs", "max_rel"};


/* ---- the sweep file ---------------------------------------------------------------------- */

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
    return PST_EINPUT;
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

/* One grid object: keys and their value lists. */
static int read_grid(pctx *c, const cJSON *g, int gi, int listed, pst_sweep *sw)
{
    json_step steps[3] = {{"grid", 0}, {NULL, gi}, {NULL, 0}};
    int d0 = listed ? 2 : 1;
    if (!cJSON_IsObject(g))
        return perr(c, steps, d0, "grid", "expected an object of key: [values]");
    int k = 0;
    const cJSON *item;
    cJSON_ArrayForEach(item, g)
    {
        const char *key = item->string;
        steps[d0] = (json_step){key, 0};
        char full[300];
        snprintf(full, sizeof full, "grid.%s", key);
        if (k >= SW_MAX_KEYS)
            return perr(c, steps, d0 + 1, full, "more than %d grid keys", SW_MAX_KEYS);
        if (!scene_key_known(key))
            return perr(c, steps, d0 + 1, full, "unknown scene key (pstencil help scene lists "
                                                "them; list items are numbered from 0)");
        for (int q = 0; q < k && gi == 0; ++q)
            if (strcmp(sw->keys[q], key) == 0)
                return perr(c, steps, d0 + 1, full, "repeated key");
        if (gi == 0) {
            sw->keys[k] = pst_strdup(key);
            if (!sw->keys[k])
                return PST_ENOMEM;
            sw->nkeys = k + 1;
        } else if (k >= sw->nkeys || strcmp(sw->keys[k], key) != 0) {
            return perr(c, steps, d0 + 1, full, "every grid object must have the keys of the "
                                                "first, in the same order");
        }
        int n;
        if (cJSON_IsArray(item)) {
            n = cJSON_GetArraySize(item);
            if (n == 0)
                return perr(c, steps, d0 + 1, full, "empty list of values");
            sw->values[gi][k] = calloc((size_t)n, sizeof(char *));
            if (!sw->values[gi][k])
                return PST_ENOMEM;
            sw->nvalues[gi][k] = n;
            for (int v = 0; v < n; ++v)
                if (!(sw->values[gi][k][v] = value_text(cJSON_GetArrayItem(item, v))))
                    return PST_ENOMEM;
        } else if (cJSON_IsObject(item)) {
            const cJSON *from = cJSON_GetObjectItemCaseSensitive(item, "from"),
                        *count = cJSON_GetObjectItemCaseSensitive(item, "count"),
                        *step = cJSON_GetObjectItemCaseSensitive(item, "step"), *m;
            cJSON_ArrayForEach(m, item)
            {
                if (strcmp(m->string, "from") && strcmp(m->string, "count") &&
                    strcmp(m->string, "step")) {
                    steps[d0 + 1] = (json_step){m->string, 0};
                    char sub[340];
                    snprintf(sub, sizeof sub, "%s.%s", full, m->string);
                    return perr(c, steps, d0 + 2, sub, "unknown key (a range is {from, count"
                                                       "[, step]})");
                }
            }
            if (!cJSON_IsNumber(from) || !cJSON_IsNumber(count) || count->valuedouble < 1 ||
                count->valuedouble > 1e6 || count->valuedouble != floor(count->valuedouble) ||
                (step && !cJSON_IsNumber(step)))
                return perr(c, steps, d0 + 1, full, "a range needs a number 'from' and a "
                                                    "whole 'count' >= 1 (and a number 'step')");
            n = (int)count->valuedouble;
            double s = step ? step->valuedouble : 1;
            sw->values[gi][k] = calloc((size_t)n, sizeof(char *));
            if (!sw->values[gi][k])
                return PST_ENOMEM;
            sw->nvalues[gi][k] = n;
            for (int v = 0; v < n; ++v) {
                cJSON *num = cJSON_CreateNumber(from->valuedouble + s * v);
                sw->values[gi][k][v] = num ? value_text(num) : NULL;
                cJSON_Delete(num);
                if (!sw->values[gi][k][v])
                    return PST_ENOMEM;
            }
        } else {
            return perr(c, steps, d0 + 1, full, "expected a list of values or a range "
                                                "{\"from\": A, \"count\": N}");
        }
        ++k;
    }
    if (k == 0)
        return perr(c, steps, d0, "grid", "no keys");
    if (gi > 0 && k != sw->nkeys)
        return perr(c, steps, d0, "grid", "every grid object must have the keys of the first");
    return PST_OK;
}

static int read_sweep(pctx *c, const cJSON *root, pst_sweep *sw)
{
    json_step steps[3] = {{NULL, 0}};
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
    }
    /* scene */
    const cJSON *scene = cJSON_GetObjectItemCaseSensitive(root, "scene");
    steps[0] = (json_step){"scene", 0};
    if (cJSON_IsString(scene)) {
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
        if (!sw->scene_text) {
            perr(c, steps, 1, "scene", "%s", msg);
            return st;
        }
    } else if (cJSON_IsObject(scene)) {
        sw->scene_path = pst_strdup(c->path);
        sw->scene_text = inline_scene(c);
        if (!sw->scene_path || !sw->scene_text)
            return PST_ENOMEM;
    } else {
        return perr(c, steps, scene ? 1 : 0, "scene",
                    scene ? "expected a scene file name or a scene object" : "required");
    }
    /* grid */
    const cJSON *grid = cJSON_GetObjectItemCaseSensitive(root, "grid");
    steps[0] = (json_step){"grid", 0};
    if (!grid)
        return perr(c, steps, 0, "grid", "required");
    if (cJSON_IsArray(grid)) {
        int n = cJSON_GetArraySize(grid);
        if (n == 0 || n > SW_MAX_GRIDS)
            return perr(c, steps, 1, "grid", "a list of 1 to %d grid objects", SW_MAX_GRIDS);
        for (int g = 0; g < n; ++g) {
            int st = read_grid(c, cJSON_GetArrayItem(grid, g), g, 1, sw);
            if (st != PST_OK)
                return st;
            sw->ngrids = g + 1;
        }
    } else {
        int st = read_grid(c, grid, 0, 0, sw);
        if (st != PST_OK)
            return st;
        sw->ngrids = 1;
    }
    sw->ncombos = 0;
    for (int g = 0; g < sw->ngrids; ++g) {
        size_t p = 1;
        for (int k = 0; k < sw->nkeys; ++k)
            p *= (size_t)sw->nvalues[g][k];
        sw->ncombos += p;
    }
    /* overrides */
    const cJSON *ov = cJSON_GetObjectItemCaseSensitive(root, "overrides");
    steps[0] = (json_step){"overrides", 0};
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
    /* output */
    const cJSON *out = cJSON_GetObjectItemCaseSensitive(root, "output");
    steps[0] = (json_step){"output", 0};
    if (out && !cJSON_IsObject(out))
        return perr(c, steps, 1, "output", "expected an object {csv, summary}");
    cJSON_ArrayForEach(m, out)
    {
        steps[1] = (json_step){m->string, 0};
        char full[300];
        snprintf(full, sizeof full, "output.%s", m->string);
        char **dst = strcmp(m->string, "csv") == 0       ? &sw->csv
                     : strcmp(m->string, "summary") == 0 ? &sw->summary
                                                         : NULL;
        if (!dst)
            return perr(c, steps, 2, full, "unknown key (output has csv and summary)");
        if (!cJSON_IsString(m) || !m->valuestring[0])
            return perr(c, steps, 2, full, "expected a file name");
        if (!(*dst = pst_strdup(m->valuestring)))
            return PST_ENOMEM;
    }
    /* default outputs: the sweep file's stem, in the working directory */
    const char *base = strrchr(c->path, '/') ? strrchr(c->path, '/') + 1 : c->path;
    const char *dot = strrchr(base, '.');
    int stem = dot ? (int)(dot - base) : (int)strlen(base);
    char name[512];
    if (!sw->csv) {
        snprintf(name, sizeof name, "%.*s.csv", stem, base);
        if (!(sw->csv = pst_strdup(name)))
            return PST_ENOMEM;
    }
    if (!sw->summary) {
        snprintf(name, sizeof name, "%.*s.summary.json", stem, base);
        if (!(sw->summary = pst_strdup(name)))
            return PST_ENOMEM;
    }
    /* slope_key, repeat_key */
    const char *names[2] = {"slope_key", "repeat_key"}, *defs[2] = {"cloud.spacing", "cloud.seed"};
    char **dsts[2] = {&sw->slope_key, &sw->repeat_key};
    for (int q = 0; q < 2; ++q) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, names[q]);
        steps[0] = (json_step){names[q], 0};
        if (v && (!cJSON_IsString(v) || !scene_key_known(v->valuestring)))
            return perr(c, steps, 1, names[q], "expected a scene key");
        if (!(*dsts[q] = pst_strdup(v ? v->valuestring : defs[q])))
            return PST_ENOMEM;
    }
    if (strcmp(sw->slope_key, sw->repeat_key) == 0) {
        steps[0] = (json_step){"repeat_key", 0};
        return perr(c, steps, 1, "repeat_key", "the same key as slope_key");
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
    free(sw->slope_key);
    free(sw->repeat_key);
    memset(sw, 0, sizeof *sw);
}

/* Overrides of one run: outputs off, the fixed ones, then the grid's. */
static int run_overrides(const pst_sweep *sw, size_t k, char **ov, int *nov)
{
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(sw, k, vals);
    int n = 0;
    ov[n++] = pst_strdup("outputs={}");
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

static void free_overrides(char **ov, int n)
{
    for (int q = 0; q < n; ++q)
        free(ov[q]);
}

/* The scene of combination k: the sweep's scene text with the combination's overrides.
 * PST_ENOMEM when the overrides cannot be built; otherwise pst_scene_parse's status, with its
 * message in msg. */
static int combo_scene(const pst_sweep *sw, size_t k, pst_scene *s, char *msg, size_t msglen)
{
    char *ov[SW_MAX_OVERRIDES + SW_MAX_KEYS + 1];
    int nov = 0;
    if (run_overrides(sw, k, ov, &nov) != PST_OK) {
        free_overrides(ov, nov);
        return PST_ENOMEM;
    }
    int ps = pst_scene_parse(s, sw->scene_text, sw->scene_path, (const char *const *)ov, nov,
                             msg, msglen);
    free_overrides(ov, nov);
    return ps;
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

/* "key=value key=value" of a combination, for messages. */
static void combo_label(const pst_sweep *sw, size_t k, char *buf, size_t len)
{
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(sw, k, vals);
    size_t n = 0;
    buf[0] = '\0';
    for (int q = 0; q < sw->nkeys && n < len; ++q)
        n += (size_t)snprintf(buf + n, len - n, "%s%s=%s", q ? " " : "", sw->keys[q], vals[q]);
}

int pst_sweep_check(const pst_sweep *sw, size_t *nfailed, char *err, size_t errlen)
{
    int first = PST_OK;
    size_t bad = 0;
    err[0] = '\0';
    for (size_t k = 0; k < sw->ncombos; ++k) {
        char *ov[SW_MAX_OVERRIDES + SW_MAX_KEYS + 1];
        int nov = 0;
        int st = run_overrides(sw, k, ov, &nov);
        pst_scene s;
        char msg[PST_ERRLEN * 2];
        if (st == PST_OK)
            st = pst_scene_parse(&s, sw->scene_text, sw->scene_path, (const char *const *)ov,
                                 nov, msg, sizeof msg);
        free_overrides(ov, nov);
        if (st == PST_OK) {
            pst_plan p;
            st = pst_plan_make(&p, &s, pst_plan_particles(&s), msg, sizeof msg);
            pst_scene_free(&s);
        }
        if (st != PST_OK) {
            if (first == PST_OK) {
                char label[512];
                combo_label(sw, k, label, sizeof label);
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

/* ---- CSV cells ----------------------------------------------------------------------------- */

static void put_cell(FILE *f, const char *s)
{
    if (!strpbrk(s, ",\"\r\n")) {
        fputs(s, f);
        return;
    }
    fputc('"', f);
    for (; *s; ++s) {
        if (*s == '"')
            fputc('"', f);
        fputc(*s, f);
    }
    fputc('"', f);
}

/* The CSV cell of a grid value: a JSON string's text, anything else its compact JSON. */
static char *key_cell(const char *json)
{
    cJSON *v = cJSON_Parse(json);
    char *out = v && cJSON_IsString(v) ? pst_strdup(v->valuestring) : pst_strdup(json);
    cJSON_Delete(v);
    return out;
}

static char *num_cell(double v)
{
    char buf[40];
    snprintf(buf, sizeof buf, "%.17g", v);
    return pst_strdup(buf);
}

/* ---- rows ---------------------------------------------------------------------------------- */

typedef struct {
    char **cells; /* nrows * ncols */
    size_t nrows, cap;
} rowset;

typedef struct {
    const pst_sweep *sw;
    int ncols;
    rowset *runs; /* per combination */
    size_t ncombos;
} csv_job;

static char **new_row(rowset *rs, int ncols)
{
    if (rs->nrows == rs->cap) {
        size_t cap = rs->cap ? 2 * rs->cap : 4;
        char **g = realloc(rs->cells, cap * (size_t)ncols * sizeof *g);
        if (!g)
            return NULL;
        rs->cells = g;
        rs->cap = cap;
    }
    char **row = rs->cells + rs->nrows * (size_t)ncols;
    memset(row, 0, (size_t)ncols * sizeof *row);
    rs->nrows++;
    return row;
}

static void rowset_clear(rowset *rs, int ncols)
{
    for (size_t i = 0; i < rs->nrows * (size_t)ncols; ++i)
        free(rs->cells[i]);
    free(rs->cells);
    memset(rs, 0, sizeof *rs);
}

static const cJSON *get(const cJSON *o, const char *k)
{
    return cJSON_GetObjectItemCaseSensitive(o, k);
}

static char *num_of(const cJSON *v)
{
    return cJSON_IsNumber(v) ? num_cell(v->valuedouble) : NULL;
}

/* Rows of one run from its report, or failed rows (one per scene task, or one) when `report`
 * is NULL. Missing cells become "". */
static int add_rows(csv_job *j, size_t k, const cJSON *report, const pst_scene *s,
                    const char *message)
{
    const pst_sweep *sw = j->sw;
    rowset *rs = &j->runs[k];
    const char *vals[SW_MAX_KEYS];
    pst_sweep_combo(sw, k, vals);
    const int nk = sw->nkeys, nc = j->ncols;
    static const char *const types[] = {"laplacian", "divergence", "gradient",
                                        "hessian",   "interpolate", "solve"};
    const cJSON *tasks = report ? get(report, "tasks") : NULL;
    int ntasks = report ? cJSON_GetArraySize(tasks) : (s ? s->ntasks : 0);
    if (ntasks == 0)
        ntasks = 1;
    for (int t = 0; t < ntasks; ++t) {
        char **row = new_row(rs, nc);
        if (!row)
            return PST_ENOMEM;
        for (int q = 0; q < nk; ++q)
            row[q] = key_cell(vals[q]);
        char **c = row + nk;
        if (!report) {
            if (s && t < s->ntasks) {
                c[C_DIM] = num_cell(s->dim);
                c[C_TASK] = pst_strdup(s->tasks[t].name);
                c[C_TYPE] = pst_strdup(types[s->tasks[t].type]);
            }
            c[C_STATUS] = pst_strdup("failed");
            c[C_MESSAGE] = pst_strdup(message ? message : "");
        } else {
            const cJSON *tj = cJSON_GetArrayItem(tasks, t), *plan = get(report, "plan"),
                        *tim = get(report, "timers"), *sv = get(tj, "solver");
            c[C_DIM] = num_of(get(report, "dim"));
            c[C_PARTICLES] = num_of(get(plan, "particles"));
            c[C_NEIGH] = num_of(get(plan, "neighbours_estimate"));
            c[C_TASK] = pst_strdup(tj ? cJSON_GetStringValue(get(tj, "name")) : "");
            c[C_TYPE] = pst_strdup(tj ? cJSON_GetStringValue(get(tj, "type")) : "");
            for (int q = 0; q < 7; ++q)
                c[C_NORM0 + q] = num_of(get(get(tj, "norms"), norm_cols[q]));
            int notconv = 0;
            if (sv) {
                c[C_ITER] = num_of(get(sv, "iterations"));
                c[C_CONV] = pst_strdup(cJSON_IsTrue(get(sv, "converged")) ? "1" : "0");
                c[C_RESID] = num_of(get(sv, "relative_residual"));
                notconv = !cJSON_IsTrue(get(sv, "converged"));
            }
            c[C_T_CLOUD] = num_of(get(tim, "cloud"));
            c[C_T_NEIGH] = num_of(get(tim, "neighbours"));
            /* phases and row counts summed over the run's operators */
            const cJSON *ops = get(report, "operators"), *op;
            double ph[5] = {0}, rows[5] = {0};
            int nops = 0;
            cJSON_ArrayForEach(op, ops)
            {
                ++nops;
                for (int q = 0; q < 5; ++q) {
                    ph[q] += cJSON_GetNumberValue(get(get(op, "phases"), pst_phase_name(q)));
                    const cJSON *rv = get(get(op, "row_status"), pst_row_status_name(q));
                    rows[q] += cJSON_IsNumber(rv) ? rv->valuedouble : 0;
                }
            }
            for (int q = 0; q < 5 && nops; ++q) {
                c[C_T_GEOM + q] = num_cell(ph[q]);
                c[C_ROWS0 + q] = num_cell(rows[q]);
            }
            c[C_T_TASK] = num_of(get(tj, "seconds"));
            c[C_T_TOTAL] = num_of(get(tim, "total"));
            c[C_CPU] = num_of(get(tim, "cpu"));
            c[C_RSS] = num_of(get(report, "peak_rss_bytes"));
            c[C_MEM] = num_of(get(get(plan, "memory_estimate_bytes"), "total"));
            c[C_STATUS] = pst_strdup(notconv ? "not-converged" : "ok");
            c[C_MESSAGE] =
                pst_strdup(notconv ? cJSON_GetStringValue(get(sv, "message")) ? cJSON_GetStringValue(
                                                                                get(sv, "message"))
                                                                          : ""
                               : "");
        }
        for (int q = 0; q < nc; ++q)
            if (!row[q] && !(row[q] = pst_strdup("")))
                return PST_ENOMEM;
    }
    return PST_OK;
}

static void write_csv(FILE *f, const void *job)
{
    const csv_job *j = job;
    for (int q = 0; q < j->sw->nkeys; ++q) {
        put_cell(f, j->sw->keys[q]);
        fputc(',', f);
    }
    for (int q = 0; q < pst_sweep_ncolumns; ++q) {
        fputs(pst_sweep_columns[q], f);
        fputc(q + 1 < pst_sweep_ncolumns ? ',' : '\n', f);
    }
    for (size_t k = 0; k < j->ncombos; ++k)
        for (size_t r = 0; r < j->runs[k].nrows; ++r) {
            char **row = j->runs[k].cells + r * (size_t)j->ncols;
            for (int q = 0; q < j->ncols; ++q) {
                put_cell(f, row[q]);
                fputc(q + 1 < j->ncols ? ',' : '\n', f);
            }
        }
}

/* The written rows as a table (for the summary): the same cells. */
static int job_table(const csv_job *j, pst_csv_table *t)
{
    size_t n = 0;
    for (size_t k = 0; k < j->ncombos; ++k)
        n += j->runs[k].nrows;
    t->ncols = j->ncols;
    t->nrows = n;
    t->cell = calloc((n + 1) * (size_t)j->ncols, sizeof *t->cell);
    if (!t->cell)
        return PST_ENOMEM;
    for (int q = 0; q < j->ncols; ++q)
        t->cell[q] = (char *)(q < j->sw->nkeys ? j->sw->keys[q]
                                               : pst_sweep_columns[q - j->sw->nkeys]);
    size_t r = 1;
    for (size_t k = 0; k < j->ncombos; ++k)
        for (size_t i = 0; i < j->runs[k].nrows; ++i, ++r)
            memcpy(t->cell + r * (size_t)j->ncols, j->runs[k].cells + i * (size_t)j->ncols,
                   (size_t)j->ncols * sizeof(char *));
    return PST_OK;
}

/* ---- reading a CSV ------------------------------------------------------------------------- */

void pst_csv_table_free(pst_csv_table *t)
{
    if (!t)
        return;
    for (size_t i = 0; t->cell && i < (t->nrows + 1) * (size_t)t->ncols; ++i)
        free(t->cell[i]);
    free(t->cell);
    memset(t, 0, sizeof *t);
}

int pst_csv_read(const char *path, pst_csv_table *t, char *err, size_t errlen)
{
    memset(t, 0, sizeof *t);
    int st = PST_OK;
    char *text = pst_read_text(path, NULL, err, errlen, &st);
    if (!text)
        return st;
    size_t cap = 64, n = 0, line = 1, row_start = 0;
    char **cells = malloc(cap * sizeof *cells);
    size_t bcap = 256, blen = 0;
    char *buf = malloc(bcap);
    int ncols = -1, incell = 0;
    const char *p = text;
    st = cells && buf ? PST_OK : PST_ENOMEM;
    while (st == PST_OK && *p) {
        /* one cell */
        blen = 0;
        if (*p == '"') {
            ++p;
            for (;;) {
                if (!*p) {
                    snprintf(err, errlen, "%s:%zu: unterminated quoted cell", path, line);
                    st = PST_EINPUT;
                    break;
                }
                if (*p == '"' && p[1] == '"') {
                    p += 2;
                    buf[blen++] = '"';
                } else if (*p == '"') {
                    ++p;
                    break;
                } else {
                    if (*p == '\n')
                        ++line;
                    buf[blen++] = *p++;
                }
                if (blen + 2 >= bcap) {
                    char *g = realloc(buf, bcap *= 2);
                    if (!g) {
                        st = PST_ENOMEM;
                        break;
                    }
                    buf = g;
                }
            }
            if (st == PST_OK && *p && *p != ',' && *p != '\n' && *p != '\r') {
                snprintf(err, errlen, "%s:%zu: text after a quoted cell", path, line);
                st = PST_EINPUT;
            }
        } else {
            while (*p && *p != ',' && *p != '\n' && *p != '\r') {
                buf[blen++] = *p++;
                if (blen + 2 >= bcap) {
                    char *g = realloc(buf, bcap *= 2);
                    if (!g) {
                        st = PST_ENOMEM;
                        break;
                    }
                    buf = g;
                }
            }
        }
        if (st != PST_OK)
            break;
        buf[blen] = '\0';
        if (n == cap) {
            char **g = realloc(cells, (cap *= 2) * sizeof *cells);
            if (!g) {
                st = PST_ENOMEM;
                break;
            }
            cells = g;
        }
        if (!(cells[n++] = pst_strdup(buf))) {
            st = PST_ENOMEM;
            break;
        }
        incell = 1;
        if (*p == ',') {
            ++p;
            continue;
        }
        /* end of a row */
        if (*p == '\r')
            ++p;
        if (*p == '\n')
            ++p;
        size_t got = n - row_start;
        if (ncols < 0) {
            ncols = (int)got;
        } else if (got != (size_t)ncols) {
            snprintf(err, errlen, "%s:%zu: %zu cells, the header has %d", path, line, got, ncols);
            st = PST_EINPUT;
        }
        row_start = n;
        incell = 0;
        ++line;
    }
    (void)incell;
    if (st == PST_OK && n != row_start) {
        snprintf(err, errlen, "%s:%zu: incomplete last row", path, line);
        st = PST_EINPUT;
    }
    if (st == PST_OK && ncols < 0) {
        snprintf(err, errlen, "%s: empty file", path);
        st = PST_EINPUT;
    }
    free(buf);
    free(text);
    if (st != PST_OK) {
        for (size_t i = 0; cells && i < n; ++i)
            free(cells[i]);
        free(cells);
        if (st == PST_ENOMEM)
            snprintf(err, errlen, "%s: out of memory", path);
        return st;
    }
    t->ncols = ncols;
    t->nrows = n / (size_t)ncols - 1;
    t->cell = cells;
    return PST_OK;
}

/* ---- the summary --------------------------------------------------------------------------- */

int pst_csv_column(const pst_csv_table *t, const char *name, int below)
{
    for (int q = 0; q < below && q < t->ncols; ++q)
        if (strcmp(t->cell[q], name) == 0)
            return q;
    return -1;
}

int pst_csv_number(const char *s, double *v)
{
    if (!s || !*s)
        return 0;
    char *end;
    double x = strtod(s, &end);
    if (*end || !isfinite(x))
        return 0;
    *v = x;
    return 1;
}

/* A CSV cell as a typed JSON value: a number, bool or list when it reads as one, else a
 * string. */
static cJSON *typed(const char *cell)
{
    cJSON *v = cJSON_Parse(cell);
    if (v && (cJSON_IsNumber(v) || cJSON_IsBool(v) || cJSON_IsArray(v) || cJSON_IsObject(v)))
        return v;
    cJSON_Delete(v);
    return cJSON_CreateString(cell);
}

static const char *const stat_cols[] = {"rel_l2", "qsfdi11", "qsfdi11_normalised", "lv78",
                                        "lv95", "max_abs", "max_rel", "t_cloud",
                                        "t_neighbours", "t_geometry", "t_moments", "t_inversion",
                                        "t_weights", "t_precompute", "t_task", "t_total", "cpu",
                                        "peak_rss_bytes", "iterations"};
enum { NSTAT = sizeof stat_cols / sizeof stat_cols[0] };

void pst_mean_std(const double *v, size_t n, double *mean, double *sd)
{
    double s = 0;
    for (size_t i = 0; i < n; ++i)
        s += v[i];
    *mean = s / (double)n;
    double q = 0;
    for (size_t i = 0; i < n; ++i)
        q += (v[i] - *mean) * (v[i] - *mean);
    *sd = n > 1 ? sqrt(q / (double)(n - 1)) : NAN;
}

/* Rows grouped by the key cells except `skip` columns, and the task: the first row of each
 * group in order of appearance, and each row's group. */
static size_t group_rows(const pst_csv_table *t, int nkeys, const int *skip, int task_col,
                         size_t *gid, size_t *first)
{
    size_t ng = 0;
    for (size_t r = 1; r <= t->nrows; ++r) {
        char **row = t->cell + r * (size_t)t->ncols;
        size_t g = 0;
        for (; g < ng; ++g) {
            char **o = t->cell + first[g] * (size_t)t->ncols;
            int same = strcmp(o[task_col], row[task_col]) == 0;
            for (int q = 0; same && q < nkeys; ++q)
                same = skip[q] || strcmp(o[q], row[q]) == 0;
            if (same)
                break;
        }
        if (g == ng)
            first[ng++] = r;
        gid[r - 1] = g;
    }
    return ng;
}

static cJSON *key_object(const pst_csv_table *t, size_t r, int nkeys, const int *skip)
{
    cJSON *k = cJSON_CreateObject();
    for (int q = 0; q < nkeys; ++q)
        if (!skip[q])
            cJSON_AddItemToObject(k, t->cell[q], typed(t->cell[r * (size_t)t->ncols + q]));
    return k;
}

static void add_number_or_null(cJSON *o, const char *name, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, name, v);
    else
        cJSON_AddNullToObject(o, name);
}

cJSON *pst_sweep_summary(const pst_csv_table *t, const char *slope_key, const char *repeat_key)
{
    const int nkeys = pst_csv_column(t, "dim", t->ncols);
    if (nkeys < 0 || nkeys > 4 * SW_MAX_KEYS || t->ncols != nkeys + pst_sweep_ncolumns)
        return NULL;
    for (int q = 0; q < pst_sweep_ncolumns; ++q)
        if (strcmp(t->cell[nkeys + q], pst_sweep_columns[q]) != 0)
            return NULL;
    const int task_col = nkeys + C_TASK, status_col = nkeys + C_STATUS;
    const int slope = pst_csv_column(t, slope_key, t->ncols), repeat = pst_csv_column(t, repeat_key, t->ncols);
    int stat_col[NSTAT];
    for (int q = 0; q < NSTAT; ++q)
        stat_col[q] = pst_csv_column(t, stat_cols[q], t->ncols);
    size_t n = t->nrows;
    size_t *gid = malloc((n + 1) * sizeof *gid), *first = malloc((n + 1) * sizeof *first);
    double *vals = malloc((n + 1) * sizeof *vals);
    cJSON *sum = cJSON_CreateObject();
    if (!gid || !first || !vals || !sum) {
        free(gid);
        free(first);
        free(vals);
        cJSON_Delete(sum);
        return NULL;
    }
    cJSON *keys = cJSON_AddArrayToObject(sum, "keys");
    for (int q = 0; q < nkeys; ++q)
        cJSON_AddItemToArray(keys, cJSON_CreateString(t->cell[q]));
    cJSON_AddStringToObject(sum, "slope_key", slope_key);
    cJSON_AddStringToObject(sum, "repeat_key", repeat_key);
    long st_ok = 0, st_nc = 0, st_failed = 0;
    for (size_t r = 1; r <= n; ++r) {
        const char *s = t->cell[r * (size_t)t->ncols + status_col];
        st_ok += strcmp(s, "ok") == 0;
        st_nc += strcmp(s, "not-converged") == 0;
        st_failed += strcmp(s, "failed") == 0;
    }
    cJSON *rows = cJSON_AddObjectToObject(sum, "rows");
    cJSON_AddNumberToObject(rows, "total", (double)n);
    cJSON_AddNumberToObject(rows, "ok", (double)st_ok);
    cJSON_AddNumberToObject(rows, "not-converged", (double)st_nc);
    cJSON_AddNumberToObject(rows, "failed", (double)st_failed);

    /* groups: all keys but repeat_key, per task; statistics over rows with status ok */
    int skip[SW_MAX_KEYS * 4] = {0};
    for (int q = 0; q < nkeys && q < (int)(sizeof skip / sizeof skip[0]); ++q)
        skip[q] = q == repeat;
    size_t ng = group_rows(t, nkeys, skip, task_col, gid, first);
    cJSON *groups = cJSON_AddArrayToObject(sum, "groups");
    for (size_t g = 0; g < ng; ++g) {
        cJSON *gj = cJSON_CreateObject();
        cJSON_AddItemToArray(groups, gj);
        cJSON_AddItemToObject(gj, "key", key_object(t, first[g], nkeys, skip));
        cJSON_AddStringToObject(gj, "task", t->cell[first[g] * (size_t)t->ncols + task_col]);
        long count = 0, total = 0;
        for (size_t r = 1; r <= n; ++r)
            if (gid[r - 1] == g) {
                ++total;
                count += strcmp(t->cell[r * (size_t)t->ncols + status_col], "ok") == 0;
            }
        cJSON_AddNumberToObject(gj, "count", (double)count);
        cJSON_AddNumberToObject(gj, "not_ok", (double)(total - count));
        cJSON *mean = cJSON_AddObjectToObject(gj, "mean"), *sd = cJSON_AddObjectToObject(gj, "std");
        for (int q = 0; q < NSTAT; ++q) {
            if (stat_col[q] < 0)
                continue;
            long m = 0;
            for (size_t r = 1; r <= n; ++r) {
                char **row = t->cell + r * (size_t)t->ncols;
                if (gid[r - 1] == g && strcmp(row[status_col], "ok") == 0 &&
                    pst_csv_number(row[stat_col[q]], &vals[m]))
                    ++m;
            }
            if (m == 0)
                continue;
            double mu, s;
            pst_mean_std(vals, (size_t)m, &mu, &s);
            add_number_or_null(mean, stat_cols[q], mu);
            if (q + 1 < NSTAT) /* iterations: the mean only */
                add_number_or_null(sd, stat_cols[q], s);
        }
    }

    /* fits: all keys but slope_key and repeat_key, per task; per norm, the mean over the
     * repeats at each resolution, then log(mean) against log(resolution) */
    cJSON *fits = cJSON_AddArrayToObject(sum, "fits");
    if (slope >= 0 && slope < nkeys) {
        for (int q = 0; q < nkeys && q < (int)(sizeof skip / sizeof skip[0]); ++q)
            skip[q] = q == repeat || q == slope;
        ng = group_rows(t, nkeys, skip, task_col, gid, first);
        double *res = malloc((n + 1) * sizeof *res);
        const char **rescell = malloc((n + 1) * sizeof *rescell);
        for (size_t g = 0; res && rescell && g < ng; ++g) {
            /* the resolutions of this group, in order of appearance */
            size_t nres = 0;
            for (size_t r = 1; r <= n; ++r) {
                if (gid[r - 1] != g)
                    continue;
                const char *c = t->cell[r * (size_t)t->ncols + slope];
                size_t q = 0;
                while (q < nres && strcmp(rescell[q], c) != 0)
                    ++q;
                if (q == nres && pst_csv_number(c, &res[nres]) && res[nres] > 0)
                    rescell[nres++] = c;
            }
            for (int nq = 0; nq < 7; ++nq) {
                int col = nkeys + C_NORM0 + nq;
                double xs[512], ys[512], rx[512], ry[512];
                int np = 0;
                for (size_t q = 0; q < nres && np < 512; ++q) {
                    double s = 0;
                    long m = 0;
                    for (size_t r = 1; r <= n; ++r) {
                        char **row = t->cell + r * (size_t)t->ncols;
                        double v;
                        if (gid[r - 1] == g && strcmp(row[slope], rescell[q]) == 0 &&
                            strcmp(row[status_col], "ok") == 0 && pst_csv_number(row[col], &v)) {
                            s += v;
                            ++m;
                        }
                    }
                    if (m > 0 && s > 0) {
                        rx[np] = res[q];
                        ry[np] = s / (double)m;
                        xs[np] = log(rx[np]);
                        ys[np] = log(ry[np]);
                        ++np;
                    }
                }
                if (np == 0)
                    continue;
                cJSON *fj = cJSON_CreateObject();
                cJSON_AddItemToArray(fits, fj);
                cJSON_AddItemToObject(fj, "key", key_object(t, first[g], nkeys, skip));
                cJSON_AddStringToObject(fj, "task",
                                        t->cell[first[g] * (size_t)t->ncols + task_col]);
                cJSON_AddStringToObject(fj, "norm", norm_cols[nq]);
                cJSON_AddNumberToObject(fj, "points", np);
                double slope_v = NAN, se = NAN;
                if (np >= 2) {
                    double mx = 0, my = 0;
                    for (int i = 0; i < np; ++i) {
                        mx += xs[i];
                        my += ys[i];
                    }
                    mx /= np;
                    my /= np;
                    double sxx = 0, sxy = 0;
                    for (int i = 0; i < np; ++i) {
                        sxx += (xs[i] - mx) * (xs[i] - mx);
                        sxy += (xs[i] - mx) * (ys[i] - my);
                    }
                    if (sxx > 0) {
                        slope_v = sxy / sxx;
                        if (np >= 3) {
                            double ssr = 0;
                            for (int i = 0; i < np; ++i) {
                                double e = ys[i] - my - slope_v * (xs[i] - mx);
                                ssr += e * e;
                            }
                            se = sqrt(ssr / (np - 2) / sxx);
                        }
                    }
                }
                add_number_or_null(fj, "slope", slope_v);
                add_number_or_null(fj, "stderr", se);
                cJSON *xa = cJSON_AddArrayToObject(fj, "resolution"),
                      *ya = cJSON_AddArrayToObject(fj, "mean");
                for (int i = 0; i < np; ++i) {
                    cJSON_AddItemToArray(xa, cJSON_CreateNumber(rx[i]));
                    cJSON_AddItemToArray(ya, cJSON_CreateNumber(ry[i]));
                }
            }
        }
        free(res);
        free(rescell);
    }
    free(gid);
    free(first);
    free(vals);
    return sum;
}

/* ---- the run ------------------------------------------------------------------------------- */

typedef struct {
    const pst_sweep *sw;
    const csv_job *j;
    const cJSON *machine;
} summary_job;

static void write_json(FILE *f, const void *job)
{
    char *text = cJSON_Print(job);
    if (text) {
        fputs(text, f);
        fputc('\n', f);
    }
    free(text);
}

/* The distinct operator parameters over the sweep's combinations (report_parameters), from
 * the scenes themselves, so that resumed runs count too. A combination whose scene does not
 * parse has none. */
static cJSON *sweep_parameters(const pst_sweep *sw)
{
    cJSON *list = cJSON_CreateArray();
    for (size_t k = 0; list && k < sw->ncombos; ++k) {
        pst_scene s;
        char msg[PST_ERRLEN * 2];
        if (combo_scene(sw, k, &s, msg, sizeof msg) != PST_OK)
            continue;
        pst_op_opts oo;
        pst_scene_op_opts(&s, &oo);
        cJSON *p = report_parameters(&oo), *q;
        pst_scene_free(&s);
        int seen = 0;
        cJSON_ArrayForEach(q, list)
            seen |= cJSON_Compare(p, q, 1);
        if (seen)
            cJSON_Delete(p);
        else
            cJSON_AddItemToArray(list, p);
    }
    return list;
}

static int write_summary(const pst_sweep *sw, const csv_job *j, const cJSON *machine, char *err,
                         size_t errlen)
{
    pst_csv_table t;
    if (job_table(j, &t) != PST_OK) {
        snprintf(err, errlen, "out of memory for the summary");
        return PST_ENOMEM;
    }
    cJSON *s = pst_sweep_summary(&t, sw->slope_key, sw->repeat_key);
    free(t.cell); /* the cells are the job's */
    if (!s) {
        snprintf(err, errlen, "out of memory for the summary");
        return PST_ENOMEM;
    }
    /* what the CSV does not hold: where it came from, the operators' parameters, the machine */
    cJSON_AddStringToObject(s, "sweep", sw->path);
    cJSON_AddItemToObject(s, "operator_parameters", sweep_parameters(sw));
    cJSON_AddStringToObject(s, "csv", sw->csv);
    const cJSON *m;
    cJSON_ArrayForEach(m, machine)
        cJSON_AddItemToObject(s, m->string, cJSON_Duplicate(m, 1));
    char msg[PST_ERRLEN];
    int st = pst_write_atomic(sw->summary, write_json, s, msg);
    cJSON_Delete(s);
    if (st != PST_OK)
        snprintf(err, errlen, "output.summary: %s", msg);
    return st;
}

/* --resume: take the rows of an existing CSV whose combination has no failed row. */
static int resume_rows(const pst_sweep *sw, csv_job *j, char *done, pst_sweep_stats *stats,
                       char *err, size_t errlen)
{
    FILE *f = fopen(sw->csv, "rb");
    if (!f)
        return PST_OK; /* nothing to resume: a fresh sweep */
    fclose(f);
    pst_csv_table t;
    char msg[PST_ERRLEN + 256];
    int st = pst_csv_read(sw->csv, &t, msg, sizeof msg);
    if (st != PST_OK) {
        snprintf(err, errlen, "--resume: %s", msg);
        return st;
    }
    const int nk = sw->nkeys, nc = j->ncols;
    int same = t.ncols == nc;
    for (int q = 0; same && q < nc; ++q)
        same = strcmp(t.cell[q], q < nk ? sw->keys[q] : pst_sweep_columns[q - nk]) == 0;
    if (!same) {
        snprintf(err, errlen, "--resume: %s: the header differs from this sweep's (grid keys "
                              "then the sweep columns); move the file away or fix the sweep",
                 sw->csv);
        pst_csv_table_free(&t);
        return PST_EINPUT;
    }
    /* the key cells of every combination */
    char **ck = calloc(sw->ncombos * (size_t)nk + 1, sizeof *ck);
    char *bad = calloc(sw->ncombos + 1, 1);
    st = ck && bad ? PST_OK : PST_ENOMEM;
    for (size_t k = 0; st == PST_OK && k < sw->ncombos; ++k) {
        const char *vals[SW_MAX_KEYS];
        pst_sweep_combo(sw, k, vals);
        for (int q = 0; q < nk; ++q)
            if (!(ck[k * (size_t)nk + q] = key_cell(vals[q])))
                st = PST_ENOMEM;
    }
    size_t hint = 0;
    for (size_t r = 1; st == PST_OK && r <= t.nrows; ++r) {
        char **row = t.cell + r * (size_t)nc;
        size_t k = sw->ncombos;
        for (size_t s = 0; s < sw->ncombos; ++s) {
            size_t c = (hint + s) % sw->ncombos;
            int eq = 1;
            for (int q = 0; eq && q < nk; ++q)
                eq = strcmp(ck[c * (size_t)nk + q], row[q]) == 0;
            if (eq) {
                k = c;
                break;
            }
        }
        if (k == sw->ncombos) {
            stats->dropped++;
            continue;
        }
        hint = k;
        char **dst = new_row(&j->runs[k], nc);
        if (!dst) {
            st = PST_ENOMEM;
            break;
        }
        memcpy(dst, row, (size_t)nc * sizeof *dst);
        memset(row, 0, (size_t)nc * sizeof *row);
        if (strcmp(dst[nk + C_STATUS], "ok") != 0 && strcmp(dst[nk + C_STATUS], "not-converged"))
            bad[k] = 1;
    }
    for (size_t k = 0; st == PST_OK && k < sw->ncombos; ++k) {
        if (j->runs[k].nrows > 0 && !bad[k])
            done[k] = 1;
        else
            rowset_clear(&j->runs[k], nc);
    }
    for (size_t i = 0; ck && i < sw->ncombos * (size_t)nk; ++i)
        free(ck[i]);
    free(ck);
    free(bad);
    pst_csv_table_free(&t);
    if (st == PST_ENOMEM)
        snprintf(err, errlen, "--resume: out of memory");
    return st;
}

int pst_sweep_run(const pst_sweep *sw, const pst_sweep_opts *o, pst_sweep_stats *stats,
                  char *err, size_t errlen)
{
    pst_sweep_stats local;
    if (!stats)
        stats = &local;
    memset(stats, 0, sizeof *stats);
    err[0] = '\0';
    csv_job j = {.sw = sw, .ncols = sw->nkeys + pst_sweep_ncolumns, .ncombos = sw->ncombos};
    j.runs = calloc(sw->ncombos + 1, sizeof *j.runs);
    char *done = calloc(sw->ncombos + 1, 1);
    int st = j.runs && done ? PST_OK : PST_ENOMEM;
    if (st == PST_ENOMEM)
        snprintf(err, errlen, "out of memory");
    if (st == PST_OK && o->resume)
        st = resume_rows(sw, &j, done, stats, err, errlen);
    cli_progress pg;
    progress_begin(&pg, !o->quiet, "sweep");
    size_t todo = 0, made = 0;
    for (size_t k = 0; k < sw->ncombos; ++k)
        todo += !done[k];
    for (size_t k = 0; st == PST_OK && k < sw->ncombos; ++k) {
        if (done[k]) {
            stats->skipped++;
            continue;
        }
        char label[512], detail[160];
        combo_label(sw, k, label, sizeof label);
        snprintf(detail, sizeof detail, "run %zu/%zu: %.100s", made + 1, todo, label);
        progress_update(&pg, todo ? (double)made / (double)todo : 1, detail);
        pst_scene s;
        char msg[PST_ERRLEN * 2];
        int ps = combo_scene(sw, k, &s, msg, sizeof msg);
        if (ps == PST_ENOMEM) {
            st = ps;
            snprintf(err, errlen, "out of memory");
            break;
        }
        if (ps != PST_OK) {
            st = add_rows(&j, k, NULL, NULL, msg);
            stats->failed++;
        } else {
            cJSON *rep = NULL;
            pst_run_opts ro = {.quiet = 1, .report = &rep};
            int rs = pst_run_scene(&s, &ro, NULL, NULL, NULL, msg, sizeof msg);
            stats->runs++;
            if (rep) {
                st = add_rows(&j, k, rep, &s, NULL);
                stats->not_converged += rs == PST_ENUMERIC;
            } else {
                st = add_rows(&j, k, NULL, &s, msg);
                stats->failed++;
            }
            cJSON_Delete(rep);
            pst_scene_free(&s);
        }
        ++made;
        if (st != PST_OK) {
            snprintf(err, errlen, "out of memory for the rows");
            break;
        }
        char wmsg[PST_ERRLEN];
        st = pst_write_atomic(sw->csv, write_csv, &j, wmsg);
        if (st != PST_OK)
            snprintf(err, errlen, "output.csv: %s", wmsg);
    }
    progress_end(&pg);
    if (st == PST_OK) { /* also when nothing ran (everything resumed) */
        char wmsg[PST_ERRLEN];
        st = pst_write_atomic(sw->csv, write_csv, &j, wmsg);
        if (st != PST_OK)
            snprintf(err, errlen, "output.csv: %s", wmsg);
    }
    if (st == PST_OK)
        st = write_summary(sw, &j, o->machine, err, errlen);
    for (size_t k = 0; k < sw->ncombos; ++k) {
        stats->rows += j.runs ? j.runs[k].nrows : 0;
        if (j.runs)
            rowset_clear(&j.runs[k], j.ncols);
    }
    free(j.runs);
    free(done);
    return st;
}
