/* Scene loading: JSON text (cJSON) -> overrides -> a check of every key against the parameter
 * table (scene_params.c) -> a pst_scene with every default filled in -> the checks that
 * involve several keys. Errors name the key and its line:column in the text (json_pos.c), or
 * the override that produced the key. The walk keeps the path from the root as a stack of
 * steps, so that any check can report where it is. */
#include "scene.h"

#include "pstencil.h"
#include "json_pos.h"
#include "scene_default_json.h"
#include "text_file.h"

#include <cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Deeper than any key of the table (tasks.N.boundary.N.where is 5 steps). */
enum { MAX_DEPTH = 16, TPATH_LEN = 128 };

typedef struct {
    const cJSON *node;
    int override; /* index of the override that made it */
} mark;

typedef struct {
    const char *text, *path;
    char *err;
    size_t errlen;
    int dim;
    json_step steps[MAX_DEPTH];
    const cJSON *nodes[MAX_DEPTH]; /* nodes[k]: the value steps[0..k] lead to */
    char index_names[MAX_DEPTH][12];
    int depth;
    const char *const *overrides;
    mark *marks;
    int nmarks, cap_marks;
    int status; /* PST_ENOMEM when an allocation failed */
} ctx;

/* ---- strings ------------------------------------------------------------------------------ */


/* Levenshtein distance, capped: strings longer than 63 bytes are "far" from everything. */
static int edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la > 63 || lb > 63)
        return 1000;
    int row[64];
    for (size_t j = 0; j <= lb; ++j)
        row[j] = (int)j;
    for (size_t i = 1; i <= la; ++i) {
        int diag = row[0];
        row[0] = (int)i;
        for (size_t j = 1; j <= lb; ++j) {
            int up = row[j];
            int best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best)
                best = up + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* Keep `cand` in *best when it is closer to `word` than the best so far and close enough to
 * be a likely typo. */
static void consider(const char *word, const char *cand, const char **best, int *bestd)
{
    int d = edit_distance(word, cand);
    int len = (int)strlen(word);
    if (d <= 2 && d < len && d < *bestd) {
        *best = cand;
        *bestd = d;
    }
}

/* Index of `word` in the '|'-separated list `values`, or -1. */
static int value_index(const char *values, const char *word)
{
    size_t wl = strlen(word);
    int k = 0;
    for (const char *p = values;; ++k) {
        const char *bar = strchr(p, '|');
        size_t n = bar ? (size_t)(bar - p) : strlen(p);
        if (n == wl && strncmp(p, word, n) == 0)
            return k;
        if (!bar)
            return -1;
        p = bar + 1;
    }
}

/* "a|b|c" as "a, b, c". */
static const char *listed(const char *values, char *buf, size_t len)
{
    size_t used = 0;
    buf[0] = '\0';
    for (const char *q = values; *q && used + 1 < len;) {
        size_t n = strcspn(q, "|");
        int w = snprintf(buf + used, len - used, "%s%.*s", used ? ", " : "", (int)n, q);
        if (w < 0)
            break;
        used += (size_t)w;
        q += n + (q[n] == '|');
    }
    return buf;
}

/* ---- messages ----------------------------------------------------------------------------- */

/* The concrete key of steps[0..depth) plus `extra`: "tasks.0.boundary.1.where". */
static void concrete_key(const ctx *c, int depth, const char *extra, char *buf, size_t len)
{
    size_t used = 0;
    buf[0] = '\0';
    for (int k = 0; k <= depth; ++k) {
        const char *part = k < depth ? (c->steps[k].key ? c->steps[k].key : c->index_names[k])
                                     : extra;
        if (!part)
            break;
        int n = snprintf(buf + used, len - used, "%s%s", used ? "." : "", part);
        if (n < 0 || (size_t)n >= len - used)
            break;
        used += (size_t)n;
    }
}

/* The override that made a node on the current path (or the member `extra` of the top node),
 * or -1 when everything comes from the text. */
static int override_of(const ctx *c, const char *extra)
{
    const cJSON *extra_node = NULL;
    if (extra && c->depth > 0 && cJSON_IsObject(c->nodes[c->depth - 1]))
        extra_node = cJSON_GetObjectItemCaseSensitive(c->nodes[c->depth - 1], extra);
    for (int m = c->nmarks - 1; m >= 0; --m) { /* the newest first: a replaced node's address
                                                  may have been reused */
        if (c->marks[m].node == extra_node)
            return c->marks[m].override;
        for (int k = 0; k < c->depth; ++k)
            if (c->marks[m].node == c->nodes[k])
                return c->marks[m].override;
    }
    return -1;
}

/* Report an error at the current path (plus the member `extra`, which need not exist):
 * "PATH:LINE:COL: key 'K': MESSAGE", or "override 'O': key 'K': MESSAGE". Returns
 * PST_EINPUT. */
static int report(ctx *c, const char *extra, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int report(ctx *c, const char *extra, const char *fmt, ...)
{
    char msg[PST_ERRLEN], key[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (!c->err || c->errlen == 0)
        return PST_EINPUT;
    concrete_key(c, c->depth, extra, key, sizeof key);
    int ov = override_of(c, extra);
    if (ov >= 0) {
        snprintf(c->err, c->errlen, "override '%s': key '%s': %s", c->overrides[ov], key, msg);
        return PST_EINPUT;
    }
    json_step steps[MAX_DEPTH + 1];
    memcpy(steps, c->steps, sizeof c->steps);
    int depth = c->depth;
    if (extra)
        steps[depth++] = (json_step){.key = extra, .index = 0};
    int line, col;
    json_pos_find(c->text, steps, depth, &line, &col);
    if (depth == 0)
        snprintf(c->err, c->errlen, "%s:%d:%d: %s", c->path, line, col, msg);
    else
        snprintf(c->err, c->errlen, "%s:%d:%d: key '%s': %s", c->path, line, col, key, msg);
    return PST_EINPUT;
}

static void push(ctx *c, const cJSON *node, const char *key, int index)
{
    /* The table's keys are never deeper than MAX_DEPTH, and the walk enters only them. */
    c->steps[c->depth] = (json_step){.key = key, .index = index};
    c->nodes[c->depth] = node;
    if (!key)
        snprintf(c->index_names[c->depth], sizeof c->index_names[0], "%d", index);
    ++c->depth;
}

static void pop(ctx *c) { --c->depth; }

/* Push an object member, counting which occurrence of its name it is (duplicates are kept by
 * cJSON, and positions must find the right one). */
static void push_member(ctx *c, const cJSON *child)
{
    int occurrence = 0;
    for (const cJSON *s = child->prev; s && s->next; s = s->prev) /* the head's prev is the tail */
        occurrence += s->string && strcmp(s->string, child->string) == 0;
    push(c, child, child->string, occurrence);
}

static const char *json_kind(const cJSON *v)
{
    if (cJSON_IsNumber(v))
        return "a number";
    if (cJSON_IsString(v))
        return "a string";
    if (cJSON_IsBool(v))
        return "a boolean";
    if (cJSON_IsNull(v))
        return "null";
    if (cJSON_IsArray(v))
        return "a list";
    if (cJSON_IsObject(v))
        return "an object";
    return "an invalid value";
}

static const char *expected_kind(sc_type t)
{
    switch (t) {
    case SC_T_INT: return "an integer";
    case SC_T_REAL: return "a number";
    case SC_T_BOOL: return "true or false";
    case SC_T_EXPR: return "an expression (a string)";
    case SC_T_EXPRS: return "an expression (a string) or a list of expressions";
    case SC_T_VEC: return "a list of numbers";
    case SC_T_PATH: return "a file name (a string)";
    case SC_T_OBJECT: return "an object";
    case SC_T_LIST: return "a list";
    case SC_T_ENUM_OR_OBJECT: return "a string or an object";
    case SC_T_STRING:
    case SC_T_ENUM: break;
    }
    return "a string";
}

/* ---- the table ---------------------------------------------------------------------------- */

/* The table entry of member `name` of an object whose table path is `parent` ("" at the
 * root): the key itself, or a map entry "<name>". */
static const sc_param *member_param(const char *parent, const char *name)
{
    char key[TPATH_LEN];
    if (strpbrk(name, ".[]<>")) /* table syntax, never part of a real key */
        return NULL;
    if (snprintf(key, sizeof key, "%s%s%s", parent, *parent ? "." : "", name) >= TPATH_LEN)
        return NULL; /* longer than any key */
    const sc_param *p = sc_param_find(key);
    if (p)
        return p;
    snprintf(key, sizeof key, "%s%s<name>", parent, *parent ? "." : "");
    return sc_param_find(key);
}

/* The table path under which an object's members are found: "tasks[]" for a list's items. */
static void child_path(const sc_param *p, int list_item, char *buf)
{
    snprintf(buf, TPATH_LEN, "%s%s", p->key, list_item ? "[]" : "");
}

/* The last segment of a table key: "rtol" of "tasks[].rtol". */
static const char *last_segment(const char *key)
{
    const char *dot = strrchr(key, '.');
    return dot ? dot + 1 : key;
}

/* 1 when `key` is a direct member of the object at table path `parent`. */
static int is_member_of(const char *key, const char *parent)
{
    size_t n = strlen(parent);
    if (n == 0)
        return strchr(key, '.') == NULL;
    return strncmp(key, parent, n) == 0 && key[n] == '.' && !strchr(key + n + 1, '.');
}

/* The closest member name of `parent` to `name`, or NULL. */
static const char *suggest_member(const char *parent, const char *name)
{
    const char *best = NULL;
    int bestd = 1000;
    for (int i = 0; i < sc_nparams; ++i)
        if (is_member_of(sc_params[i].key, parent) && !strchr(sc_params[i].key, '<'))
            consider(name, last_segment(sc_params[i].key), &best, &bestd);
    return best;
}

/* The selector among the members of `parent` (tasks[].type, cloud.source, mobility.type). */
static const sc_param *selector_of(const char *parent)
{
    for (int i = 0; i < sc_nparams; ++i)
        if ((sc_params[i].flags & SC_F_SELECTOR) && is_member_of(sc_params[i].key, parent))
            return &sc_params[i];
    return NULL;
}

/* ---- checking one value against its entry -------------------------------------------------- */

static int check_value(ctx *c, const cJSON *v, const sc_param *p, sc_type type);

/* Numbers: finite, whole for integers, within the range and the allowed values. */
static int check_number(ctx *c, const cJSON *v, const sc_param *p, sc_type type)
{
    if (!cJSON_IsNumber(v))
        return report(c, NULL, "expected %s, got %s", expected_kind(type), json_kind(v));
    double x = v->valuedouble;
    if (!isfinite(x))
        return report(c, NULL, "number out of range (not a finite double)");
    if (type == SC_T_INT && (x != floor(x) || fabs(x) > 9007199254740991.0))
        return report(c, NULL, "expected an integer, got %.15g", x);
    if (type == SC_T_INT && p->values) {
        char word[32];
        snprintf(word, sizeof word, "%.0f", x);
        if (value_index(p->values, word) < 0)
            return report(c, NULL, "must be one of %s, got %.0f",
                          listed(p->values, word, sizeof word), x);
    }
    int below = p->lo_kind && (p->lo_kind == '[' ? x < p->lo : x <= p->lo);
    int above = p->hi_kind && (p->hi_kind == ']' ? x > p->hi : x >= p->hi);
    if (!below && !above)
        return PST_OK;
    if (p->lo_kind && p->hi_kind)
        return report(c, NULL, "must be in %c%.15g, %.15g%c, got %.15g", p->lo_kind, p->lo,
                      p->hi, p->hi_kind, x);
    if (p->lo_kind)
        return report(c, NULL, "must be %s %.15g, got %.15g", p->lo_kind == '[' ? ">=" : ">",
                      p->lo, x);
    return report(c, NULL, "must be %s %.15g, got %.15g", p->hi_kind == ']' ? "<=" : "<", p->hi,
                  x);
}

static int check_enum(ctx *c, const cJSON *v, const sc_param *p)
{
    if (!cJSON_IsString(v))
        return report(c, NULL, "expected a string, got %s", json_kind(v));
    const char *s = v->valuestring, *best = NULL;
    int bestd = 1000;
    char list[512] = "";
    if (p->values) {
        if (value_index(p->values, s) >= 0)
            return PST_OK;
        char word[64];
        for (const char *q = p->values; *q;) {
            size_t n = strcspn(q, "|");
            snprintf(word, sizeof word, "%.*s", (int)n, q);
            /* consider() keeps a pointer: point into the table, not into `word` */
            int before = bestd;
            consider(s, word, &best, &bestd);
            if (bestd < before)
                best = q;
            size_t used = strlen(list);
            snprintf(list + used, sizeof list - used, "%s%s", used ? ", " : "", word);
            q += n + (q[n] == '|');
        }
        if (best) {
            size_t n = strcspn(best, "|");
            return report(c, NULL, "unknown value '%s' (one of %s; did you mean '%.*s'?)", s,
                          list, (int)n, best);
        }
        return report(c, NULL, "unknown value '%s' (one of %s)", s, list);
    }
    for (int i = 0; i < pst_scheme_count(); ++i) { /* no values: a registered scheme */
        const char *name = pst_scheme_name(i);
        if (strcmp(name, s) == 0)
            return PST_OK;
        consider(s, name, &best, &bestd);
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s%s", used ? ", " : "", name);
    }
    if (best)
        return report(c, NULL, "unknown scheme '%s' (one of %s; did you mean '%s'?)", s, list,
                      best);
    return report(c, NULL, "unknown scheme '%s' (one of %s)", s, list);
}

static int check_expr(ctx *c, const cJSON *v, sc_type type)
{
    /* A number is a constant expression ("rhs": 0, "tasks.0.exact=8"): keep it as its text so
     * that the runner sees one kind of value. */
    if (cJSON_IsNumber(v) && isfinite(v->valuedouble)) {
        char text[32];
        snprintf(text, sizeof text, "%.17g", v->valuedouble);
        char *copy = malloc(strlen(text) + 1);
        if (!copy)
            return report(c, NULL, "out of memory");
        strcpy(copy, text);
        cJSON *w = (cJSON *)v; /* the tree is the parser's own copy */
        w->type = cJSON_String;
        w->valuestring = copy;
    }
    if (!cJSON_IsString(v))
        return report(c, NULL, "expected %s, got %s", expected_kind(type), json_kind(v));
    if (v->valuestring[strspn(v->valuestring, " \t\r\n")] == '\0')
        return report(c, NULL, "the expression is empty");
    return PST_OK;
}

/* Items of a list: each is checked at its own index. */
static int check_items(ctx *c, const cJSON *v, const sc_param *p, sc_type item,
                       const sc_param *range)
{
    int n = 0, rc = PST_OK;
    for (const cJSON *e = v->child; e && rc == PST_OK; e = e->next, ++n) {
        push(c, e, NULL, n);
        if (range && range->hi_kind && n >= (int)range->hi)
            rc = report(c, NULL, "too many items in '%s' (at most %d)", last_segment(p->key),
                        (int)range->hi);
        else
            rc = check_value(c, e, p, item);
        pop(c);
    }
    return rc;
}

static int check_object(ctx *c, const cJSON *obj, const sc_param *p, const char *tpath);

static int check_value(ctx *c, const cJSON *v, const sc_param *p, sc_type type)
{
    switch (type) {
    case SC_T_INT:
    case SC_T_REAL: return check_number(c, v, p, type);
    case SC_T_BOOL:
        return cJSON_IsBool(v) ? PST_OK
                               : report(c, NULL, "expected true or false, got %s", json_kind(v));
    case SC_T_STRING:
        return cJSON_IsString(v) ? PST_OK
                                 : report(c, NULL, "expected a string, got %s", json_kind(v));
    case SC_T_PATH:
        if (!cJSON_IsString(v))
            return report(c, NULL, "expected a file name (a string), got %s", json_kind(v));
        return *v->valuestring ? PST_OK : report(c, NULL, "the file name is empty");
    case SC_T_ENUM: return check_enum(c, v, p);
    case SC_T_EXPR: return check_expr(c, v, type);
    case SC_T_EXPRS: {
        if (!cJSON_IsArray(v))
            return check_expr(c, v, type);
        int n = cJSON_GetArraySize(v);
        if (n < 1 || n > 6)
            return report(c, NULL, "expected 1 to 6 expressions, got %d", n);
        return check_items(c, v, p, SC_T_EXPR, NULL);
    }
    case SC_T_VEC: {
        if (!cJSON_IsArray(v))
            return report(c, NULL, "expected a list of %d numbers, got %s", c->dim, json_kind(v));
        int n = cJSON_GetArraySize(v);
        if (n != c->dim)
            return report(c, NULL, "expected %d numbers (dim = %d), got %d", c->dim, c->dim, n);
        return check_items(c, v, p, SC_T_REAL, NULL);
    }
    case SC_T_LIST:
        if (!cJSON_IsArray(v))
            return report(c, NULL, "expected a list, got %s", json_kind(v));
        if (p->item == SC_T_OBJECT) {
            char tpath[TPATH_LEN];
            child_path(p, 1, tpath);
            int n = 0, rc = PST_OK;
            for (const cJSON *e = v->child; e && rc == PST_OK; e = e->next, ++n) {
                push(c, e, NULL, n);
                if (p->hi_kind && n >= (int)p->hi)
                    rc = report(c, NULL, "too many items in '%s' (at most %d)",
                                last_segment(p->key), (int)p->hi);
                else
                    rc = check_object(c, e, p, tpath);
                pop(c);
            }
            return rc;
        }
        return check_items(c, v, p, p->item, p);
    case SC_T_ENUM_OR_OBJECT:
        if (cJSON_IsString(v))
            return check_enum(c, v, p);
        if (!cJSON_IsObject(v))
            return report(c, NULL, "expected a string or an object, got %s", json_kind(v));
        return check_object(c, v, p, p->key);
    case SC_T_OBJECT: return check_object(c, v, p, p->key);
    }
    return PST_OK;
}

/* The condition of a selector: "PREP tasks of type solve" or "when 'cloud.source' is file". */
static const char *condition(const sc_param *sel, const char *applies, const char *prep,
                             char *buf, size_t len)
{
    char values[256];
    listed(applies, values, sizeof values);
    if (strcmp(sel->key, "tasks[].type") == 0)
        snprintf(buf, len, "%s tasks of type %s", prep, values);
    else
        snprintf(buf, len, "when '%s' is %s", sel->key, values);
    return buf;
}

/* An object's members: the selector first (it decides which members apply), then every member
 * in text order, then the required members that are missing. */
static int check_object(ctx *c, const cJSON *obj, const sc_param *p, const char *tpath)
{
    if (!cJSON_IsObject(obj))
        return report(c, NULL, "expected an object, got %s", json_kind(obj));
    const sc_param *sel = selector_of(tpath);
    const char *selected = NULL; /* the selector's value when given and valid */
    int rc;
    const cJSON *sv = sel ? cJSON_GetObjectItemCaseSensitive(obj, last_segment(sel->key)) : NULL;
    if (sv) {
        push_member(c, sv);
        rc = check_value(c, sv, sel, sel->type);
        pop(c);
        if (rc != PST_OK)
            return rc;
        selected = sv->valuestring;
    } else if (sel && sel->def) {
        selected = sel->def + 1; /* "\"lattice\"": compared up to the closing quote below */
    }
    int count = 0;
    for (const cJSON *m = obj->child; m; m = m->next, ++count) {
        push_member(c, m);
        const sc_param *mp = member_param(tpath, m->string);
        rc = PST_OK;
        if (c->steps[c->depth - 1].index > 0) {
            rc = report(c, NULL, "duplicate key (an earlier '%s' is in the same object)",
                        m->string);
        } else if (p && p->hi_kind && p->type == SC_T_OBJECT && count >= (int)p->hi) {
            rc = report(c, NULL, "too many entries in '%s' (at most %d)", last_segment(p->key),
                        (int)p->hi);
        } else if (!mp) {
            const char *best = suggest_member(tpath, m->string);
            char key[256];
            concrete_key(c, c->depth - 1, best, key, sizeof key);
            rc = best ? report(c, NULL, "unknown key (did you mean '%s'?)", key)
                      : report(c, NULL, "unknown key");
        } else if (mp->applies && sel && selected) {
            char word[64];
            snprintf(word, sizeof word, "%.*s", (int)strcspn(selected, "\""), selected);
            char cond[300];
            if (value_index(mp->applies, word) < 0)
                rc = report(c, NULL, "applies only %s",
                            condition(sel, mp->applies, "to", cond, sizeof cond));
        }
        if (rc == PST_OK && mp && mp != sel)
            rc = check_value(c, m, mp, mp->type);
        pop(c);
        if (rc != PST_OK)
            return rc;
    }
    for (int i = 0; i < sc_nparams; ++i) {
        const sc_param *q = &sc_params[i];
        if (!(q->flags & SC_F_REQUIRED) || !is_member_of(q->key, tpath))
            continue;
        const char *name = last_segment(q->key);
        if (cJSON_GetObjectItemCaseSensitive(obj, name))
            continue;
        if (q->applies) {
            if (!sel || !selected)
                continue; /* the missing selector is reported instead */
            char word[64];
            snprintf(word, sizeof word, "%.*s", (int)strcspn(selected, "\""), selected);
            if (value_index(q->applies, word) < 0)
                continue;
            char cond[300];
            return report(c, name, "missing required key (%s)",
                          condition(sel, word, "for", cond, sizeof cond));
        }
        return report(c, name, "missing required key");
    }
    return PST_OK;
}

/* ---- overrides ---------------------------------------------------------------------------- */

static int add_mark(ctx *c, const cJSON *node, int override)
{
    if (c->nmarks == c->cap_marks) {
        int cap = c->cap_marks ? 2 * c->cap_marks : 16;
        mark *m = realloc(c->marks, (size_t)cap * sizeof *m);
        if (!m)
            return c->status = PST_ENOMEM;
        c->marks = m;
        c->cap_marks = cap;
    }
    c->marks[c->nmarks++] = (mark){node, override};
    return PST_OK;
}

static int override_error(ctx *c, int idx, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int override_error(ctx *c, int idx, const char *fmt, ...)
{
    char msg[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (c->err && c->errlen)
        snprintf(c->err, c->errlen, "override '%s': %s", c->overrides[idx], msg);
    return PST_EINPUT;
}

/* Put `value` at `slot` of `parent` (a member name, or an index of a list: the end appends),
 * replacing what is there. Takes ownership of value. */
static int place(cJSON *parent, const char *name, int index, cJSON *value)
{
    cJSON *old = name ? cJSON_GetObjectItemCaseSensitive(parent, name)
                      : cJSON_GetArrayItem(parent, index);
    int ok = !old  ? (name ? cJSON_AddItemToObject(parent, name, value)
                           : cJSON_AddItemToArray(parent, value))
             : name ? cJSON_ReplaceItemInObjectCaseSensitive(parent, name, value) /* names it */
                    : cJSON_ReplaceItemViaPointer(parent, old, value);
    if (!ok) {
        cJSON_Delete(value);
        return PST_ENOMEM;
    }
    return PST_OK;
}

/* Apply "dotted.key=value": find each segment in the table, create missing objects and lists
 * on the way, and set the value (JSON when it parses as JSON, else a string). */
static int apply_override(ctx *c, cJSON *root, int idx)
{
    const char *ov = c->overrides[idx];
    const char *eq = strchr(ov, '=');
    if (!eq || eq == ov)
        return override_error(c, idx, "expected KEY=VALUE");
    /* key is cut into segments in place; shown is the key up to the current segment */
    char key[256], tpath[TPATH_LEN] = "", shown[256];
    size_t klen = (size_t)(eq - ov);
    if (klen >= sizeof key)
        return override_error(c, idx, "key too long");
    memcpy(key, ov, klen);
    key[klen] = '\0';
    cJSON *cur = root;
    const sc_param *p = NULL; /* the entry of cur (NULL: the root) */
    int in_list = 0;          /* cur is a list of p->item */
    char *save = NULL;
    for (char *seg = key;; seg = save + 1) {
        save = strchr(seg, '.');
        int last = save == NULL;
        if (save)
            *save = '\0';
        size_t sl = (size_t)(seg - key); /* the prefix before this segment, with its dot */
        memcpy(shown, ov, sl + strlen(seg));
        shown[sl + strlen(seg)] = '\0';
        const char *name = NULL;
        int index = -1;
        const sc_param *next;
        if (in_list) {
            char *end;
            errno = 0;
            long k = strtol(seg, &end, 10);
            if (!*seg || *end || seg[0] == '-' || seg[0] == '+' || errno)
                return override_error(c, idx, "key '%s': '%s' is not a list index", shown, seg);
            if (k > cJSON_GetArraySize(cur))
                return override_error(c, idx, "key '%s': index %ld is past the end of the list "
                                      "(%d items)", shown, k, cJSON_GetArraySize(cur));
            index = (int)k;
            next = p;
            size_t tl = strlen(tpath);
            snprintf(tpath + tl, sizeof tpath - tl, "[]");
        } else {
            int container = !p || p->type == SC_T_OBJECT || p->type == SC_T_ENUM_OR_OBJECT ||
                            (p->type == SC_T_LIST && p->item == SC_T_OBJECT);
            next = container && *seg ? member_param(tpath, seg) : NULL;
            if (!next) {
                const char *best = container ? suggest_member(tpath, seg) : NULL;
                if (best) {
                    char guess[256];
                    snprintf(guess, sizeof guess, "%.*s%s", (int)sl, ov, best);
                    return override_error(c, idx, "unknown key '%s' (did you mean '%s'?)",
                                          shown, guess);
                }
                return override_error(c, idx, "unknown key '%s'", shown);
            }
            name = seg;
            snprintf(tpath, sizeof tpath, "%s", next->key);
        }
        /* After an index the entry stays the list's: its items are what the next segment
         * names. */
        in_list = index < 0 && next->type == SC_T_LIST;
        if (last) {
            const char *text = eq + 1;
            cJSON *value = cJSON_ParseWithOpts(text, NULL, 1);
            if (!value)
                value = cJSON_CreateString(text);
            if (!value || place(cur, name, index, value) != PST_OK || add_mark(c, value, idx))
                return PST_ENOMEM;
            return PST_OK;
        }
        cJSON *child = name ? cJSON_GetObjectItemCaseSensitive(cur, name)
                            : cJSON_GetArrayItem(cur, index);
        int want_list = in_list;
        if (!child) {
            child = want_list ? cJSON_CreateArray() : cJSON_CreateObject();
            if (!child || place(cur, name, index, child) != PST_OK || add_mark(c, child, idx))
                return PST_ENOMEM;
        } else if (want_list ? !cJSON_IsArray(child) : !cJSON_IsObject(child)) {
            return override_error(c, idx, "key '%s': expected %s, got %s", shown,
                                  want_list ? "a list" : "an object", json_kind(child));
        }
        cur = child;
        p = next;
    }
}

/* ---- reading checked values, with the table's defaults ------------------------------------ */

static const cJSON *member(const cJSON *obj, const char *name)
{
    return cJSON_IsObject(obj) ? cJSON_GetObjectItemCaseSensitive(obj, name) : NULL;
}

/* Enter member `name` of obj for the messages that follow; the node may be absent. */
static const cJSON *enter(ctx *c, const cJSON *obj, const char *name)
{
    const cJSON *v = member(obj, name);
    if (v)
        push_member(c, v);
    else
        push(c, NULL, name, 0);
    return v;
}

/* The table's default of `key`: its text (numbers, true / false) or an enum value without its
 * quotes, in buf. */
static const char *default_text(const char *key, char *buf, size_t len)
{
    const sc_param *p = sc_param_find(key);
    const char *d = p && p->def ? p->def : "0";
    snprintf(buf, len, "%.*s", (int)strcspn(d + (*d == '"'), "\""), d + (*d == '"'));
    return buf;
}

static double get_real(const cJSON *obj, const char *key)
{
    const cJSON *v = member(obj, last_segment(key));
    char buf[64];
    return v ? v->valuedouble : strtod(default_text(key, buf, sizeof buf), NULL);
}

static int get_bool(const cJSON *obj, const char *key)
{
    const cJSON *v = member(obj, last_segment(key));
    char buf[64];
    return v ? cJSON_IsTrue(v) : strcmp(default_text(key, buf, sizeof buf), "true") == 0;
}

/* The index of an enum's value among the entry's values. */
static int get_enum(const cJSON *obj, const char *key)
{
    const cJSON *v = member(obj, last_segment(key));
    char buf[64];
    const char *word = cJSON_IsString(v) ? v->valuestring : default_text(key, buf, sizeof buf);
    return value_index(sc_param_find(key)->values, word);
}

static const char *get_string(const cJSON *obj, const char *key)
{
    const cJSON *v = member(obj, last_segment(key));
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static void get_vec(const ctx *c, const cJSON *obj, const char *key, double out[3])
{
    const cJSON *v = member(obj, last_segment(key));
    double def = get_real(NULL, key);
    for (int d = 0; d < 3; ++d) {
        const cJSON *e = v && d < c->dim ? cJSON_GetArrayItem(v, d) : NULL;
        out[d] = e ? e->valuedouble : d < c->dim ? def : 0.0;
    }
}

static int set_str(ctx *c, char **dst, const char *src)
{
    if (!src)
        return PST_OK;
    *dst = pst_strdup(src);
    return *dst ? PST_OK : (c->status = PST_ENOMEM);
}

/* An input file named in the scene, relative to the scene file's folder. */
static int set_path(ctx *c, char **dst, const char *dir, const char *file)
{
    if (!file)
        return PST_OK;
    if (file[0] == '/' || strcmp(dir, ".") == 0)
        return set_str(c, dst, file);
    size_t n = strlen(dir) + strlen(file) + 2;
    *dst = malloc(n);
    if (!*dst)
        return c->status = PST_ENOMEM;
    snprintf(*dst, n, "%s/%s", dir, file);
    return PST_OK;
}

static const char axis_name[3] = {'x', 'y', 'z'};

/* hi > lo on every axis, reported at `hi_name`. */
static int check_box(ctx *c, const double lo[3], const double hi[3], const char *hi_name)
{
    for (int d = 0; d < c->dim; ++d)
        if (!(hi[d] > lo[d]))
            return report(c, hi_name, "must exceed lo along %c (lo %.15g, hi %.15g)",
                          axis_name[d], lo[d], hi[d]);
    return PST_OK;
}

/* ---- the sections of a scene ---------------------------------------------------------------- */

static int read_cloud(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = enter(c, root, "cloud");
    sc_cloud *cl = &s->cloud;
    cl->source = (sc_cloud_source)get_enum(o, "cloud.source");
    int rc = set_path(c, &cl->file, s->dir, get_string(o, "cloud.file"));
    get_vec(c, o, "cloud.lo", cl->lo);
    get_vec(c, o, "cloud.hi", cl->hi);
    cl->spacing = get_real(o, "cloud.spacing");
    cl->jitter = get_real(o, "cloud.jitter");
    cl->seed = (long)get_real(o, "cloud.seed");
    cl->boundary_layer = get_bool(o, "cloud.boundary_layer");
    cl->angle = get_real(o, "cloud.angle");
    cl->h_ratio = get_real(o, "cloud.h_ratio");
    cl->h_ratio_set = member(o, "h_ratio") != NULL;
    if (rc == PST_OK && cl->source != SC_CLOUD_FILE) {
        rc = check_box(c, cl->lo, cl->hi, "hi");
        /* the generators' rule (generators.c): a whole number of spacings, to 1e-9 */
        for (int d = 0; d < c->dim && rc == PST_OK; ++d) {
            double r = (cl->hi[d] - cl->lo[d]) / cl->spacing, rn = round(r);
            if (!(r <= 4294967295.0) || rn < 1 || fabs(r - rn) > 1e-9 * r)
                rc = report(c, "spacing",
                            "the box length along %c (%.15g) is not a whole number of "
                            "spacings (ratio %.15g)",
                            axis_name[d], cl->hi[d] - cl->lo[d], r);
        }
    }
    pop(c);
    return rc;
}

/* An expression or a list of them into out[], with the count the context needs (`need`; 0:
 * one or dim). */
static int read_exprs(ctx *c, const cJSON *obj, const char *name, int need, const char *what,
                      char **out, int *count)
{
    const cJSON *v = member(obj, name);
    if (!v)
        return PST_OK;
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 1;
    if (need == 0 && n != 1 && n != c->dim)
        return report(c, name, "expected one expression or a list of %d (one per axis), got %d",
                      c->dim, n);
    if (need > 1 && n != need)
        return report(c, name, "%s needs a list of %d expressions, got %s%d", what, need,
                      cJSON_IsArray(v) ? "" : "a single expression, not ", n);
    if (need == 1 && n != 1)
        return report(c, name, "%s needs a single expression, got a list of %d", what, n);
    for (int k = 0; k < n; ++k) {
        const cJSON *e = cJSON_IsArray(v) ? cJSON_GetArrayItem(v, k) : v;
        if (set_str(c, &out[k], e->valuestring) != PST_OK)
            return c->status;
    }
    *count = n;
    return PST_OK;
}

static int read_mobility(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = enter(c, root, "mobility");
    sc_mobility *m = &s->mobility;
    m->type = (sc_mobility_type)get_enum(o, "mobility.type");
    m->value = m->type == SC_MOB_CONSTANT ? get_real(o, "mobility.value") : 0.0;
    m->ncomp = m->type == SC_MOB_NONE ? 0 : 1;
    int rc = read_exprs(c, o, "expression", 0, "", m->expr, &m->ncomp);
    if (rc == PST_OK)
        rc = set_path(c, &m->file, s->dir, get_string(o, "mobility.file"));
    m->layer = (int)get_real(o, "mobility.layer");
    m->i0 = (int)get_real(o, "mobility.i0");
    m->j0 = (int)get_real(o, "mobility.j0");
    pop(c);
    return rc;
}

static int read_operator(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = member(root, "operator");
    static const int kernels[] = {-1, PST_KERNEL_CUBIC, PST_KERNEL_QUINTIC,
                                  PST_KERNEL_WENDLAND_C2, PST_KERNEL_WENDLAND_C4};
    const char *scheme = get_string(o, "operator.scheme");
    char buf[64];
    s->op.kernel = kernels[get_enum(o, "operator.kernel")];
    s->op.gradient = PST_GRAD_G1 + get_enum(o, "operator.gradient");
    s->op.variant = (int)get_real(o, "operator.variant");
    s->op.cond_max = get_real(o, "operator.cond_max");
    s->op.rank_tol = get_real(o, "operator.rank_tol");
    s->op.min_pair_distance = get_real(o, "operator.min_pair_distance");
    s->op.on_degenerate = get_enum(o, "operator.on_degenerate");
    s->op.mobility_mean = get_enum(o, "operator.mobility_mean");
    return set_str(c, &s->op.scheme,
                   scheme ? scheme : default_text("operator.scheme", buf, sizeof buf));
}

static int read_fields(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = enter(c, root, "fields");
    int rc = PST_OK;
    for (const cJSON *m = o ? o->child : NULL; m && rc == PST_OK; m = m->next) {
        push_member(c, m);
        if (!pst_is_identifier(m->string))
            rc = report(c, NULL, "a field name must be a C identifier (letters, digits and _, "
                                 "not starting with a digit, at most %d characters)",
                        PST_MAX_NAME - 1);
        else if (pst_is_reserved_column(m->string))
            rc = report(c, NULL, "'%s' is a column of the CSV format, not a field name",
                        m->string);
        pop(c);
        if (rc == PST_OK) {
            sc_field *f = &s->fields[s->nfields++];
            if ((rc = set_str(c, &f->name, m->string)) == PST_OK)
                rc = set_str(c, &f->expr, m->valuestring);
        }
    }
    pop(c);
    return rc;
}

static int find_field(const pst_scene *s, const char *name)
{
    for (int k = 0; k < s->nfields; ++k)
        if (strcmp(s->fields[k].name, name) == 0)
            return k;
    return -1;
}

/* "field 'w' is not declared in 'fields' (did you mean 'u'?)" */
static int unknown_name(ctx *c, const char *extra, const char *what, const char *name,
                        const char *const *known, int nknown, const char *where)
{
    const char *best = NULL;
    int bestd = 1000;
    for (int k = 0; k < nknown; ++k)
        consider(name, known[k], &best, &bestd);
    if (best)
        return report(c, extra, "%s '%s' is not %s (did you mean '%s'?)", what, name, where,
                      best);
    return report(c, extra, "%s '%s' is not %s", what, name, where);
}

static int read_region(ctx *c, const cJSON *task, sc_task *t)
{
    const cJSON *r = member(task, "region");
    if (!cJSON_IsObject(r)) {
        t->region = (sc_region_type)get_enum(task, "tasks[].region");
        return PST_OK;
    }
    t->region = SC_REGION_BOX;
    get_vec(c, r, "tasks[].region.lo", t->region_lo);
    get_vec(c, r, "tasks[].region.hi", t->region_hi);
    enter(c, task, "region");
    int rc = check_box(c, t->region_lo, t->region_hi, "hi");
    pop(c);
    return rc;
}

static int read_points(ctx *c, const cJSON *task, pst_scene *s, sc_task *t)
{
    const cJSON *o = enter(c, task, "points");
    int rc = PST_OK;
    if (o) {
        const char *file = get_string(o, "tasks[].points.file");
        int nbox = !!member(o, "lo") + !!member(o, "hi") + !!member(o, "spacing");
        if (file && nbox)
            rc = report(c, NULL, "give either 'file' or 'lo', 'hi' and 'spacing', not both");
        else if (!file && nbox < 3)
            rc = report(c, !member(o, "lo") ? "lo" : !member(o, "hi") ? "hi" : "spacing",
                        "missing (a point lattice needs lo, hi and spacing)");
        else if (file)
            rc = set_path(c, &t->points_file, s->dir, file);
        else {
            get_vec(c, o, "tasks[].points.lo", t->points_lo);
            get_vec(c, o, "tasks[].points.hi", t->points_hi);
            t->points_spacing = get_real(o, "tasks[].points.spacing");
            rc = check_box(c, t->points_lo, t->points_hi, "hi");
        }
    }
    pop(c);
    return rc;
}

static int read_boundary(ctx *c, const cJSON *task, sc_task *t)
{
    const cJSON *list = enter(c, task, "boundary");
    int rc = PST_OK;
    for (const cJSON *g = list ? list->child : NULL; g && rc == PST_OK; g = g->next) {
        sc_group *gr = &t->groups[t->ngroups];
        push(c, g, NULL, t->ngroups);
        gr->where = (sc_side)get_enum(g, "tasks[].boundary[].where");
        gr->neumann = get_enum(g, "tasks[].boundary[].type");
        if (c->dim == 2 && (gr->where == SC_SIDE_ZLO || gr->where == SC_SIDE_ZHI))
            rc = report(c, "where", "there is no z side in 2D");
        if (rc == PST_OK && (rc = set_str(c, &gr->value, get_string(g, "value"))) == PST_OK)
            ++t->ngroups;
        pop(c);
    }
    pop(c);
    return rc;
}

static const char *const norm_names[SC_NNORMS] = {"rel_l2", "qsfdi11", "qsfdi11_normalised",
                                                  "lv78",   "lv95",    "max_abs",
                                                  "max_rel"};

static int read_norms(ctx *c, const cJSON *task, sc_task *t)
{
    const cJSON *list = member(task, "norms");
    if (!list) {
        if (t->nexact) { /* errors are wanted whenever there is something to compare with */
            t->norms[t->nnorms++] = SC_NORM_REL_L2;
            t->norms[t->nnorms++] = SC_NORM_MAX_ABS;
        }
        return PST_OK;
    }
    if (!t->nexact)
        return report(c, "norms", "error norms need an exact solution ('exact')");
    int rc = PST_OK;
    enter(c, task, "norms");
    for (const cJSON *e = list->child; e && rc == PST_OK; e = e->next) {
        int k = value_index(sc_param_find("tasks[].norms")->values, e->valuestring);
        for (int j = 0; j < t->nnorms; ++j)
            if (t->norms[j] == k) {
                push(c, e, NULL, t->nnorms);
                rc = report(c, NULL, "norm '%s' is listed twice", norm_names[k]);
                pop(c);
            }
        t->norms[t->nnorms++] = k;
    }
    pop(c);
    return rc;
}

static int read_task(ctx *c, const cJSON *o, pst_scene *s, sc_task *t)
{
    static const char *const what[] = {"a laplacian task", "a divergence task",
                                       "a gradient task", "a hessian task",
                                       "an interpolate task", "a solve task"};
    static const int stored[] = {-1, 1, 0};
    t->type = (sc_task_type)get_enum(o, "tasks[].type");
    int rc = set_str(c, &t->name, get_string(o, "tasks[].name"));
    const char *field = get_string(o, "tasks[].field");
    if (rc == PST_OK && field && find_field(s, field) < 0) {
        const char *known[SC_MAX_FIELDS];
        for (int k = 0; k < s->nfields; ++k)
            known[k] = s->fields[k].name;
        rc = unknown_name(c, "field", "field", field, known, s->nfields, "declared in 'fields'");
    }
    if (rc == PST_OK)
        rc = set_str(c, &t->field, field);
    int need = t->type == SC_TASK_GRADIENT  ? c->dim
               : t->type == SC_TASK_HESSIAN ? (c->dim == 2 ? 3 : 6)
                                            : 1;
    if (rc == PST_OK) {
        char what_dim[64];
        snprintf(what_dim, sizeof what_dim, "%s in %dD", what[t->type], c->dim);
        rc = read_exprs(c, o, "exact", need, need > 1 ? what_dim : what[t->type], t->exact,
                        &t->nexact);
    }
    if (rc == PST_OK)
        rc = read_norms(c, o, t);
    if (rc == PST_OK)
        rc = read_region(c, o, t);
    if (rc == PST_OK && t->type == SC_TASK_INTERPOLATE)
        rc = read_points(c, o, s, t);
    if (rc == PST_OK)
        rc = set_str(c, &t->rhs, get_string(o, "tasks[].rhs"));
    if (rc == PST_OK)
        rc = read_boundary(c, o, t);
    if (rc == PST_OK && t->type == SC_TASK_SOLVE && t->ngroups == 0 && t->nexact == 0)
        rc = report(c, NULL, "a solve without 'boundary' needs 'exact' (its Dirichlet values)");
    t->solver = get_enum(o, "tasks[].solver");
    t->precond = get_enum(o, "tasks[].precond");
    t->amg_source = get_enum(o, "tasks[].amg_source");
    t->restart = (int)get_real(o, "tasks[].restart");
    t->max_iter = (int)get_real(o, "tasks[].max_iter");
    t->rtol = get_real(o, "tasks[].rtol");
    t->stored = stored[get_enum(o, "tasks[].operator")];
    return rc;
}

/* 1 when `name` is a field or the name of a task before `upto`. */
static int name_taken(const pst_scene *s, const char *name, int upto)
{
    if (find_field(s, name) >= 0)
        return 1;
    for (int k = 0; k < upto; ++k)
        if (s->tasks[k].name && strcmp(s->tasks[k].name, name) == 0)
            return 1;
    return 0;
}

/* Task names: given ones are identifiers, unique, and not field names; the others become the
 * type, numbered from _2 when taken. */
static int name_tasks(ctx *c, const cJSON *list, pst_scene *s)
{
    static const char *const type_names[] = {"laplacian", "divergence", "gradient",
                                              "hessian",   "interpolate", "solve"};
    int rc = PST_OK;
    for (int i = 0; i < s->ntasks && rc == PST_OK; ++i) {
        const char *name = s->tasks[i].name;
        if (!name)
            continue;
        push(c, cJSON_GetArrayItem(list, i), NULL, i);
        if (!pst_is_identifier(name) || pst_is_reserved_column(name))
            rc = report(c, "name", "a task name must be a C identifier (at most %d characters) "
                                   "and not a CSV column name, got '%s'",
                        PST_MAX_NAME - 1, name);
        else if (find_field(s, name) >= 0)
            rc = report(c, "name", "'%s' is already the name of a field", name);
        for (int k = 0; k < i && rc == PST_OK; ++k)
            if (s->tasks[k].name && strcmp(s->tasks[k].name, name) == 0)
                rc = report(c, "name", "duplicate task name '%s' (also tasks.%d.name)", name, k);
        pop(c);
    }
    for (int i = 0; i < s->ntasks && rc == PST_OK; ++i) {
        sc_task *t = &s->tasks[i];
        if (t->name)
            continue;
        char buf[PST_MAX_NAME];
        snprintf(buf, sizeof buf, "%s", type_names[t->type]);
        for (int k = 2; name_taken(s, buf, s->ntasks); ++k)
            snprintf(buf, sizeof buf, "%s_%d", type_names[t->type], k);
        rc = set_str(c, &t->name, buf);
    }
    return rc;
}

static int read_tasks(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *list = enter(c, root, "tasks");
    int rc = PST_OK;
    for (const cJSON *o = list ? list->child : NULL; o && rc == PST_OK; o = o->next) {
        push(c, o, NULL, s->ntasks);
        rc = read_task(c, o, s, &s->tasks[s->ntasks++]);
        pop(c);
    }
    if (rc == PST_OK)
        rc = name_tasks(c, list, s);
    pop(c);
    return rc;
}

static int read_outputs(ctx *c, const cJSON *root, pst_scene *s)
{
    const cJSON *o = enter(c, root, "outputs");
    sc_outputs *out = &s->out;
    int rc = set_str(c, &out->csv, get_string(o, "outputs.csv"));
    if (rc == PST_OK)
        rc = set_str(c, &out->vtu, get_string(o, "outputs.vtu"));
    if (rc == PST_OK)
        rc = set_str(c, &out->report, get_string(o, "outputs.report"));
    const cJSON *list = member(o, "fields");
    if (list && rc == PST_OK) {
        enter(c, o, "fields");
        const char *known[SC_MAX_FIELDS + SC_MAX_TASKS];
        int nknown = 0;
        for (int k = 0; k < s->nfields; ++k)
            known[nknown++] = s->fields[k].name;
        for (int k = 0; k < s->ntasks; ++k)
            known[nknown++] = s->tasks[k].name;
        for (const cJSON *e = list->child; e && rc == PST_OK; e = e->next) {
            const char *name = e->valuestring;
            push(c, e, NULL, out->nfields);
            if (!name_taken(s, name, s->ntasks))
                rc = unknown_name(c, NULL, "name", name, known, nknown,
                                  "a field or a task name");
            for (int k = 0; k < out->nfields && rc == PST_OK; ++k)
                if (strcmp(out->fields[k], name) == 0)
                    rc = report(c, NULL, "'%s' is listed twice", name);
            pop(c);
            if (rc == PST_OK && (rc = set_str(c, &out->fields[out->nfields], name)) == PST_OK)
                ++out->nfields;
        }
        pop(c);
    }
    pop(c);
    return rc;
}

/* ---- entry points ------------------------------------------------------------------------- */

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
        return report(c, NULL, "a scene must be a JSON object, got %s", json_kind(root));
    for (int k = 0; k < noverrides; ++k) {
        int rc = apply_override(c, root, k);
        if (rc != PST_OK)
            return rc;
    }
    c->dim = 2;
    const cJSON *dim = member(root, "dim");
    if (dim) { /* every vector's length depends on it: check it first */
        push_member(c, dim);
        int rc = check_value(c, dim, sc_param_find("dim"), SC_T_INT);
        pop(c);
        if (rc != PST_OK)
            return rc;
        c->dim = (int)dim->valuedouble;
    }
    int rc = check_object(c, root, NULL, "");
    if (rc != PST_OK)
        return rc;
    s->dim = c->dim;
    const char *title = get_string(root, "title");
    if ((rc = set_str(c, &s->title, title ? title : s->path)) != PST_OK ||
        (rc = read_cloud(c, root, s)) != PST_OK || (rc = read_mobility(c, root, s)) != PST_OK ||
        (rc = read_operator(c, root, s)) != PST_OK || (rc = read_fields(c, root, s)) != PST_OK ||
        (rc = read_tasks(c, root, s)) != PST_OK || (rc = read_outputs(c, root, s)) != PST_OK)
        return rc;
    s->memory_fraction = get_real(member(root, "limits"), "limits.memory_fraction");
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
        for (int g = 0; g < t->ngroups; ++g)
            free(t->groups[g].value);
    }
    free(s->out.csv);
    free(s->out.vtu);
    free(s->out.report);
    for (int k = 0; k < s->out.nfields; ++k)
        free(s->out.fields[k]);
    memset(s, 0, sizeof *s);
}
