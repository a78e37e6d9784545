/* The walk over a scene's JSON that scene*.c share (scene.c is the entry point): the path
 * from the root as a stack of steps, so that any check can say where it is, and the marks of
 * the nodes that overrides made. Private to the scene loader; scene.h is its interface. */
#ifndef PSTENCIL_SCENE_WALK_H
#define PSTENCIL_SCENE_WALK_H

#include "scene.h"

#include "json_pos.h"

#include <cJSON.h>
#include <stddef.h>

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

/* Keep `cand` in *best when it is closer to `word` than the best so far and close enough to
 * be a likely typo. */
void scene_consider(const char *word, const char *cand, const char **best, int *bestd);
/* Index of `word` in the '|'-separated list `values`, or -1. */
int scene_value_index(const char *values, const char *word);
/* "a|b|c" as "a, b, c". */
const char *scene_listed(const char *values, char *buf, size_t len);

/* The concrete key of steps[0..depth) plus `extra`: "tasks.0.boundary.1.where". */
void scene_concrete_key(const ctx *c, int depth, const char *extra, char *buf, size_t len);
/* Report an error at the current path (plus the member `extra`, which need not exist):
 * "PATH:LINE:COL: key 'K': MESSAGE", or "override 'O': key 'K': MESSAGE". Returns
 * PST_EINPUT. */
int scene_error(ctx *c, const char *extra, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Step into `node`, member `key` (NULL: list item `index`) of the current node; pop steps
 * back out. */
void scene_push(ctx *c, const cJSON *node, const char *key, int index);
void scene_pop(ctx *c);
/* Push an object member, counting which occurrence of its name it is (duplicates are kept by
 * cJSON, and positions must find the right one). */
void scene_push_member(ctx *c, const cJSON *child);
/* What a JSON value is, and what a table type expects, for messages: "a number", "a list". */
const char *scene_json_kind(const cJSON *v);
const char *scene_expected_kind(sc_type t);

/* The table entry of member `name` of an object whose table path is `parent` ("" at the
 * root): the key itself, or a map entry "<name>". */
const sc_param *scene_member_param(const char *parent, const char *name);
/* The last segment of a table key: "rtol" of "tasks[].rtol". */
const char *scene_last_segment(const char *key);
/* The closest member name of `parent` to `name`, or NULL. */
const char *scene_suggest_member(const char *parent, const char *name);
/* Value v against table entry p read as `type` (an entry may allow two types). */
int scene_check_value(ctx *c, const cJSON *v, const sc_param *p, sc_type type);
/* An object's members: the selector first (it decides which members apply), then every member
 * in text order, then the required members that are missing. */
int scene_check_object(ctx *c, const cJSON *obj, const sc_param *p, const char *tpath);

/* Apply "dotted.key=value": find each segment in the table, create missing objects and lists
 * on the way, and set the value (JSON when it parses as JSON, else a string). */
int scene_apply_override(ctx *c, cJSON *root, int idx);

/* Refuse two of outputs.csv, .vtu, .report on one file (normalised paths), naming both keys;
 * called inside the "outputs" object. */
int scene_check_output_paths(ctx *c, const pst_scene *s);

/* Member `name` of obj, NULL when absent or obj is no object. */
const cJSON *scene_member(const cJSON *obj, const char *name);
/* Enter member `name` of obj for the messages that follow; the node may be absent. */
const cJSON *scene_enter(ctx *c, const cJSON *obj, const char *name);
/* The table's default of `key`: its text (numbers, true / false) or an enum value without its
 * quotes, in buf. */
const char *scene_default_text(const char *key, char *buf, size_t len);
/* The value at table key `key` (its last segment a member of obj), else its default. */
double scene_get_real(const cJSON *obj, const char *key);
int scene_get_bool(const cJSON *obj, const char *key);
/* The index of an enum's value among the entry's values. */
int scene_get_enum(const cJSON *obj, const char *key);
const char *scene_get_string(const cJSON *obj, const char *key);
void scene_get_vec(const ctx *c, const cJSON *obj, const char *key, double out[3]);
/* A list of dim booleans, or one for every axis, into out[0..3) (0 above dim). */
void scene_get_axes(const ctx *c, const cJSON *obj, const char *key, int out[3]);
/* A copy of src into *dst (nothing for NULL); PST_ENOMEM is kept in c->status. */
int scene_set_str(ctx *c, char **dst, const char *src);
/* An input file named in the scene, relative to the scene file's folder. */
int scene_set_path(ctx *c, char **dst, const char *dir, const char *file);

/* hi > lo on every axis, reported at `hi_name`. */
int scene_check_box(ctx *c, const double lo[3], const double hi[3], const char *hi_name);

/* Each section of the scene into s, with the checks across its keys. */
int scene_read_cloud(ctx *c, const cJSON *root, pst_scene *s);
int scene_read_mobility(ctx *c, const cJSON *root, pst_scene *s);
int scene_read_operator(ctx *c, const cJSON *root, pst_scene *s);
int scene_read_fields(ctx *c, const cJSON *root, pst_scene *s);
int scene_read_tasks(ctx *c, const cJSON *root, pst_scene *s);
int scene_read_outputs(ctx *c, const cJSON *root, pst_scene *s);
/* The boundary groups of a task (scene_boundary.c); a group's side must not lie on one of the
 * cloud's periodic axes. */
int scene_read_boundary(ctx *c, const cJSON *task, const int periodic[3], sc_task *t);
/* The keys of a diffuse task (scene_steps.c). */
int scene_read_steps(ctx *c, const cJSON *task, sc_task *t);

#endif
