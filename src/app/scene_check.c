/* The check of a scene's JSON against the parameter table (scene_params.c): every key known
 * (with a did-you-mean), every value of its entry's type and range, a selector's keys only
 * where they apply. */
#include "scene_walk.h"

#include "pstencil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The table entry of member `name` of an object whose table path is `parent` ("" at the
 * root): the key itself, or a map entry "<name>". */
const sc_param *scene_member_param(const char *parent, const char *name)
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
const char *scene_last_segment(const char *key)
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
const char *scene_suggest_member(const char *parent, const char *name)
{
    const char *best = NULL;
    int bestd = 1000;
    for (int i = 0; i < sc_nparams; ++i)
        if (is_member_of(sc_params[i].key, parent) && !strchr(sc_params[i].key, '<'))
            scene_consider(name, scene_last_segment(sc_params[i].key), &best, &bestd);
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


/* Numbers: finite, whole for integers, within the range and the allowed values. */
static int check_number(ctx *c, const cJSON *v, const sc_param *p, sc_type type)
{
    if (!cJSON_IsNumber(v))
        return scene_error(c, NULL, "expected %s, got %s", scene_expected_kind(type),
                           scene_json_kind(v));
    double x = v->valuedouble;
    if (!isfinite(x))
        return scene_error(c, NULL, "number out of range (not a finite double)");
    if (type == SC_T_INT && (x != floor(x) || fabs(x) > 9007199254740991.0))
        return scene_error(c, NULL, "expected an integer, got %.15g", x);
    if (type == SC_T_INT && p->values) {
        char word[32];
        snprintf(word, sizeof word, "%.0f", x);
        if (scene_value_index(p->values, word) < 0)
            return scene_error(c, NULL, "must be one of %s, got %.0f",
                               scene_listed(p->values, word, sizeof word), x);
    }
    int below = p->lo_kind && (p->lo_kind == '[' ? x < p->lo : x <= p->lo);
    int above = p->hi_kind && (p->hi_kind == ']' ? x > p->hi : x >= p->hi);
    if (!below && !above)
        return PST_OK;
    if (p->lo_kind && p->hi_kind)
        return scene_error(c, NULL, "must be in %c%.15g, %.15g%c, got %.15g", p->lo_kind, p->lo,
                           p->hi, p->hi_kind, x);
    if (p->lo_kind)
        return scene_error(c, NULL, "must be %s %.15g, got %.15g", p->lo_kind == '[' ? ">=" : ">",
                           p->lo, x);
    return scene_error(c, NULL, "must be %s %.15g, got %.15g", p->hi_kind == ']' ? "<=" : "<",
                       p->hi, x);
}

static int check_enum(ctx *c, const cJSON *v, const sc_param *p)
{
    if (!cJSON_IsString(v))
        return scene_error(c, NULL, "expected a string, got %s", scene_json_kind(v));
    const char *s = v->valuestring, *best = NULL;
    int bestd = 1000;
    char list[512] = "";
    if (p->values) {
        if (scene_value_index(p->values, s) >= 0)
            return PST_OK;
        char word[64];
        for (const char *q = p->values; *q;) {
            size_t n = strcspn(q, "|");
            snprintf(word, sizeof word, "%.*s", (int)n, q);
            /* scene_consider() keeps a pointer: point into the table, not into `word` */
            int before = bestd;
            scene_consider(s, word, &best, &bestd);
            if (bestd < before)
                best = q;
            size_t used = strlen(list);
            snprintf(list + used, sizeof list - used, "%s%s", used ? ", " : "", word);
            q += n + (q[n] == '|');
        }
        if (best) {
            size_t n = strcspn(best, "|");
            return scene_error(c, NULL, "unknown value '%s' (one of %s; did you mean '%.*s'?)", s,
                               list, (int)n, best);
        }
        return scene_error(c, NULL, "unknown value '%s' (one of %s)", s, list);
    }
    for (int i = 0; i < pst_scheme_count(); ++i) { /* no values: a registered scheme */
        const char *name = pst_scheme_name(i);
        if (strcmp(name, s) == 0)
            return PST_OK;
        scene_consider(s, name, &best, &bestd);
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s%s", used ? ", " : "", name);
    }
    if (best)
        return scene_error(c, NULL, "unknown scheme '%s' (one of %s; did you mean '%s'?)", s, list,
                           best);
    return scene_error(c, NULL, "unknown scheme '%s' (one of %s)", s, list);
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
            return scene_error(c, NULL, "out of memory");
        strcpy(copy, text);
        cJSON *w = (cJSON *)v; /* the tree is the parser's own copy */
        w->type = cJSON_String;
        w->valuestring = copy;
    }
    if (!cJSON_IsString(v))
        return scene_error(c, NULL, "expected %s, got %s", scene_expected_kind(type),
                           scene_json_kind(v));
    if (v->valuestring[strspn(v->valuestring, " \t\r\n")] == '\0')
        return scene_error(c, NULL, "the expression is empty");
    return PST_OK;
}

/* Items of a list: each is checked at its own index, as `item` or, with tpath, as an object
 * of the table path tpath; range (when given) bounds their number. */
static int check_items(ctx *c, const cJSON *v, const sc_param *p, sc_type item,
                       const sc_param *range, const char *tpath)
{
    int n = 0, rc = PST_OK;
    for (const cJSON *e = v->child; e && rc == PST_OK; e = e->next, ++n) {
        scene_push(c, e, NULL, n);
        if (range && range->hi_kind && n >= (int)range->hi)
            rc = scene_error(c, NULL, "too many items in '%s' (at most %d)",
                             scene_last_segment(p->key), (int)range->hi);
        else
            rc = tpath ? scene_check_object(c, e, p, tpath) : scene_check_value(c, e, p, item);
        scene_pop(c);
    }
    return rc;
}

int scene_check_value(ctx *c, const cJSON *v, const sc_param *p, sc_type type)
{
    switch (type) {
    case SC_T_INT:
    case SC_T_REAL: return check_number(c, v, p, type);
    case SC_T_BOOL:
        return cJSON_IsBool(v)
                   ? PST_OK
                   : scene_error(c, NULL, "expected true or false, got %s", scene_json_kind(v));
    case SC_T_STRING:
        return cJSON_IsString(v)
                   ? PST_OK
                   : scene_error(c, NULL, "expected a string, got %s", scene_json_kind(v));
    case SC_T_PATH:
        if (!cJSON_IsString(v))
            return scene_error(c, NULL, "expected a file name (a string), got %s",
                               scene_json_kind(v));
        return *v->valuestring ? PST_OK : scene_error(c, NULL, "the file name is empty");
    case SC_T_ENUM: return check_enum(c, v, p);
    case SC_T_EXPR: return check_expr(c, v, type);
    case SC_T_EXPRS: {
        if (!cJSON_IsArray(v))
            return check_expr(c, v, type);
        int n = cJSON_GetArraySize(v);
        if (n < 1 || n > 6)
            return scene_error(c, NULL, "expected 1 to 6 expressions, got %d", n);
        return check_items(c, v, p, SC_T_EXPR, NULL, NULL);
    }
    case SC_T_VEC: {
        if (!cJSON_IsArray(v))
            return scene_error(c, NULL, "expected a list of %d numbers, got %s", c->dim,
                               scene_json_kind(v));
        int n = cJSON_GetArraySize(v);
        if (n != c->dim)
            return scene_error(c, NULL, "expected %d numbers (dim = %d), got %d", c->dim, c->dim,
                               n);
        return check_items(c, v, p, SC_T_REAL, NULL, NULL);
    }
    case SC_T_AXES: {
        if (cJSON_IsBool(v))
            return PST_OK;
        if (!cJSON_IsArray(v))
            return scene_error(c, NULL, "expected true, false or a list of %d booleans (one per "
                               "axis), got %s", c->dim, scene_json_kind(v));
        int n = cJSON_GetArraySize(v);
        if (n != c->dim)
            return scene_error(c, NULL, "expected %d booleans (dim = %d), got %d", c->dim, c->dim,
                               n);
        return check_items(c, v, p, SC_T_BOOL, NULL, NULL);
    }
    case SC_T_LIST:
        if (!cJSON_IsArray(v))
            return scene_error(c, NULL, "expected a list, got %s", scene_json_kind(v));
        if (p->item == SC_T_OBJECT) {
            char tpath[TPATH_LEN];
            child_path(p, 1, tpath);
            return check_items(c, v, p, SC_T_OBJECT, p, tpath);
        }
        return check_items(c, v, p, p->item, p, NULL);
    case SC_T_ENUM_OR_OBJECT:
        if (cJSON_IsString(v))
            return check_enum(c, v, p);
        if (!cJSON_IsObject(v))
            return scene_error(c, NULL, "expected a string or an object, got %s",
                               scene_json_kind(v));
        return scene_check_object(c, v, p, p->key);
    case SC_T_OBJECT: return scene_check_object(c, v, p, p->key);
    }
    return PST_OK;
}

/* The condition of a selector: "PREP tasks of type solve" or "when 'cloud.source' is file". */
static const char *condition(const sc_param *sel, const char *applies, const char *prep,
                             char *buf, size_t len)
{
    char values[256];
    scene_listed(applies, values, sizeof values);
    if (strcmp(sel->key, "tasks[].type") == 0)
        snprintf(buf, len, "%s tasks of type %s", prep, values);
    else
        snprintf(buf, len, "when '%s' is %s", sel->key, values);
    return buf;
}

/* An object's members: the selector first (it decides which members apply), then every member
 * in text order, then the required members that are missing. */
int scene_check_object(ctx *c, const cJSON *obj, const sc_param *p, const char *tpath)
{
    if (!cJSON_IsObject(obj))
        return scene_error(c, NULL, "expected an object, got %s", scene_json_kind(obj));
    const sc_param *sel = selector_of(tpath);
    const char *selected = NULL; /* the selector's value when given and valid */
    int rc;
    const cJSON *sv =
        sel ? cJSON_GetObjectItemCaseSensitive(obj, scene_last_segment(sel->key)) : NULL;
    if (sv) {
        scene_push_member(c, sv);
        rc = scene_check_value(c, sv, sel, sel->type);
        scene_pop(c);
        if (rc != PST_OK)
            return rc;
        selected = sv->valuestring;
    } else if (sel && sel->def) {
        selected = sel->def + 1; /* "\"lattice\"": compared up to the closing quote below */
    }
    int count = 0;
    for (const cJSON *m = obj->child; m; m = m->next, ++count) {
        scene_push_member(c, m);
        const sc_param *mp = scene_member_param(tpath, m->string);
        rc = PST_OK;
        if (c->steps[c->depth - 1].index > 0) {
            rc = scene_error(c, NULL, "duplicate key (an earlier '%s' is in the same object)",
                             m->string);
        } else if (p && p->hi_kind && p->type == SC_T_OBJECT && count >= (int)p->hi) {
            rc = scene_error(c, NULL, "too many entries in '%s' (at most %d)",
                             scene_last_segment(p->key), (int)p->hi);
        } else if (!mp) {
            const char *best = scene_suggest_member(tpath, m->string);
            char key[256];
            scene_concrete_key(c, c->depth - 1, best, key, sizeof key);
            rc = best ? scene_error(c, NULL, "unknown key (did you mean '%s'?)", key)
                      : scene_error(c, NULL, "unknown key");
        } else if (mp->applies && sel && selected) {
            char word[64];
            snprintf(word, sizeof word, "%.*s", (int)strcspn(selected, "\""), selected);
            char cond[300];
            if (scene_value_index(mp->applies, word) < 0)
                rc = scene_error(c, NULL, "applies only %s",
                                 condition(sel, mp->applies, "to", cond, sizeof cond));
        }
        if (rc == PST_OK && mp && mp != sel)
            rc = scene_check_value(c, m, mp, mp->type);
        scene_pop(c);
        if (rc != PST_OK)
            return rc;
    }
    for (int i = 0; i < sc_nparams; ++i) {
        const sc_param *q = &sc_params[i];
        if (!(q->flags & SC_F_REQUIRED) || !is_member_of(q->key, tpath))
            continue;
        const char *name = scene_last_segment(q->key);
        if (cJSON_GetObjectItemCaseSensitive(obj, name))
            continue;
        if (q->applies) {
            if (!sel || !selected)
                continue; /* the missing selector is reported instead */
            char word[64];
            snprintf(word, sizeof word, "%.*s", (int)strcspn(selected, "\""), selected);
            if (scene_value_index(q->applies, word) < 0)
                continue;
            char cond[300];
            return scene_error(c, name, "missing required key (%s)",
                               condition(sel, word, "for", cond, sizeof cond));
        }
        return scene_error(c, name, "missing required key");
    }
    return PST_OK;
}
