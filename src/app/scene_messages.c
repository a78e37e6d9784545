/* Where a message points: the walk's path from the root, the override that made a key, and
 * the text's line:column of it (json_pos.c). */
#include "scene_walk.h"

#include "pstencil.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* The concrete key of steps[0..depth) plus `extra`: "tasks.0.boundary.1.where". */
void scene_concrete_key(const ctx *c, int depth, const char *extra, char *buf, size_t len)
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
int scene_error(ctx *c, const char *extra, const char *fmt, ...)
{
    char msg[PST_ERRLEN], key[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (!c->err || c->errlen == 0)
        return PST_EINPUT;
    scene_concrete_key(c, c->depth, extra, key, sizeof key);
    int ov = override_of(c, extra);
    if (ov >= 0) {
        snprintf(c->err, c->errlen, "override '%s': key '%s': %s", c->overrides[ov], key, msg);
        pst_escape_controls(c->err, c->errlen);
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
    pst_escape_controls(c->err, c->errlen); /* keys and values may hold any byte */
    return PST_EINPUT;
}

void scene_push(ctx *c, const cJSON *node, const char *key, int index)
{
    /* The table's keys are never deeper than MAX_DEPTH, and the walk enters only them. */
    c->steps[c->depth] = (json_step){.key = key, .index = index};
    c->nodes[c->depth] = node;
    if (!key)
        snprintf(c->index_names[c->depth], sizeof c->index_names[0], "%d", index);
    ++c->depth;
}

void scene_pop(ctx *c) { --c->depth; }

/* Push an object member, counting which occurrence of its name it is (duplicates are kept by
 * cJSON, and positions must find the right one). */
void scene_push_member(ctx *c, const cJSON *child)
{
    int occurrence = 0;
    for (const cJSON *s = child->prev; s && s->next; s = s->prev) /* the head's prev is the tail */
        occurrence += s->string && strcmp(s->string, child->string) == 0;
    scene_push(c, child, child->string, occurrence);
}

const char *scene_json_kind(const cJSON *v)
{
    static const struct {
        cJSON_bool (*is)(const cJSON *);
        const char *name;
    } kinds[] = {{cJSON_IsNumber, "a number"}, {cJSON_IsString, "a string"},
                 {cJSON_IsBool, "a boolean"},  {cJSON_IsNull, "null"},
                 {cJSON_IsArray, "a list"},     {cJSON_IsObject, "an object"}};
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; ++k)
        if (kinds[k].is(v))
            return kinds[k].name;
    return "an invalid value";
}

const char *scene_expected_kind(sc_type t)
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
    case SC_T_AXES: return "true, false or a list of booleans";
    case SC_T_STRING:
    case SC_T_ENUM: break;
    }
    return "a string";
}
