/* Command-line overrides key=value: each puts its JSON value at its key in the scene's tree
 * (making the objects and list items on the way) and marks the nodes it made, so that a
 * message about them names the override. */
#include "scene_walk.h"

#include "pstencil.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
int scene_apply_override(ctx *c, cJSON *root, int idx)
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
            next = container && *seg ? scene_member_param(tpath, seg) : NULL;
            if (!next) {
                const char *best = container ? scene_suggest_member(tpath, seg) : NULL;
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
                                  want_list ? "a list" : "an object", scene_json_kind(child));
        }
        cur = child;
        p = next;
    }
}
