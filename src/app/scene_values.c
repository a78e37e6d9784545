/* Reading values that the check passed, with the table's defaults for absent keys, and
 * copying strings and file names into the scene. */
#include "scene_walk.h"

#include "pstencil.h"
#include "text_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const cJSON *scene_member(const cJSON *obj, const char *name)
{
    return cJSON_IsObject(obj) ? cJSON_GetObjectItemCaseSensitive(obj, name) : NULL;
}

/* Enter member `name` of obj for the messages that follow; the node may be absent. */
const cJSON *scene_enter(ctx *c, const cJSON *obj, const char *name)
{
    const cJSON *v = scene_member(obj, name);
    if (v)
        scene_push_member(c, v);
    else
        scene_push(c, NULL, name, 0);
    return v;
}

/* The table's default of `key`: its text (numbers, true / false) or an enum value without its
 * quotes, in buf. */
const char *scene_default_text(const char *key, char *buf, size_t len)
{
    const sc_param *p = sc_param_find(key);
    const char *d = p && p->def ? p->def : "0";
    snprintf(buf, len, "%.*s", (int)strcspn(d + (*d == '"'), "\""), d + (*d == '"'));
    return buf;
}

double scene_get_real(const cJSON *obj, const char *key)
{
    const cJSON *v = scene_member(obj, scene_last_segment(key));
    char buf[64];
    return v ? v->valuedouble : strtod(scene_default_text(key, buf, sizeof buf), NULL);
}

int scene_get_bool(const cJSON *obj, const char *key)
{
    const cJSON *v = scene_member(obj, scene_last_segment(key));
    char buf[64];
    return v ? cJSON_IsTrue(v) : strcmp(scene_default_text(key, buf, sizeof buf), "true") == 0;
}

/* The index of an enum's value among the entry's values. */
int scene_get_enum(const cJSON *obj, const char *key)
{
    const cJSON *v = scene_member(obj, scene_last_segment(key));
    char buf[64];
    const char *word =
        cJSON_IsString(v) ? v->valuestring : scene_default_text(key, buf, sizeof buf);
    return scene_value_index(sc_param_find(key)->values, word);
}

const char *scene_get_string(const cJSON *obj, const char *key)
{
    const cJSON *v = scene_member(obj, scene_last_segment(key));
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

void scene_get_vec(const ctx *c, const cJSON *obj, const char *key, double out[3])
{
    const cJSON *v = scene_member(obj, scene_last_segment(key));
    double def = scene_get_real(NULL, key);
    for (int d = 0; d < 3; ++d) {
        const cJSON *e = v && d < c->dim ? cJSON_GetArrayItem(v, d) : NULL;
        out[d] = e ? e->valuedouble : d < c->dim ? def : 0.0;
    }
}

void scene_get_axes(const ctx *c, const cJSON *obj, const char *key, int out[3])
{
    const cJSON *v = scene_member(obj, scene_last_segment(key));
    int all = v ? cJSON_IsTrue(v) : scene_get_bool(NULL, key);
    for (int d = 0; d < 3; ++d) {
        const cJSON *e = cJSON_IsArray(v) && d < c->dim ? cJSON_GetArrayItem(v, d) : NULL;
        out[d] = d < c->dim && (e ? cJSON_IsTrue(e) : all);
    }
}

int scene_set_str(ctx *c, char **dst, const char *src)
{
    if (!src)
        return PST_OK;
    *dst = pst_strdup(src);
    return *dst ? PST_OK : (c->status = PST_ENOMEM);
}

/* An input file named in the scene, relative to the scene file's folder. */
int scene_set_path(ctx *c, char **dst, const char *dir, const char *file)
{
    if (!file)
        return PST_OK;
    if (file[0] == '/' || strcmp(dir, ".") == 0)
        return scene_set_str(c, dst, file);
    size_t n = strlen(dir) + strlen(file) + 2;
    *dst = malloc(n);
    if (!*dst)
        return c->status = PST_ENOMEM;
    snprintf(*dst, n, "%s/%s", dir, file);
    return PST_OK;
}
