/* Scenes: what a run computes, read from a JSON file (docs/scenes.md) and checked against the
 * parameter table (scene_params.c), with command-line key=value overrides.
 *
 * The loader turns the file into a pst_scene with every default filled in; the planner
 * (plan.c) decides from it what must be computed, the runner (run.c) computes it. Every string
 * in a scene is owned by the scene (pst_scene_free). */
#ifndef PSTENCIL_SCENE_H
#define PSTENCIL_SCENE_H

#include "pstencil.h"

#include <stddef.h>
#include <stdio.h>

enum { SC_MAX_TASKS = 32, SC_MAX_FIELDS = 32, SC_MAX_GROUPS = 8, SC_MAX_NORMS = 8 };

/* tasks[].precond "auto" (after none, jacobi, amg: their pst_precond values) */
enum { SC_PRECOND_AUTO = 3 };

typedef enum { SC_CLOUD_LATTICE, SC_CLOUD_CELL_CENTRED, SC_CLOUD_FILE } sc_cloud_source;

typedef struct {
    sc_cloud_source source;
    char *file;              /* CSV cloud (source "file"), resolved against the scene's folder */
    double lo[3], hi[3];     /* box of a generated cloud                                        */
    double spacing;          /* s0                                                             */
    double jitter;           /* K                                                              */
    long seed;
    int boundary_layer;      /* lattice: 1 = the outer layer is a Dirichlet boundary            */
    double angle;            /* lattice rotation, degrees                                       */
    double h_ratio;          /* h / s0 (generated clouds; a file keeps its own h unless set)    */
    int h_ratio_set;         /* 1 when the scene gave h_ratio (a file's h is then replaced)     */
    int spacing_set;         /* 1 when the scene gave spacing (a file's h_ratio then scales it) */
    int periodic[3];         /* 1 on the periodic axes (cloud.periodic; 0 above dim)            */
    double box_lo[3], box_hi[3]; /* a file cloud's periodic box (cloud.box; with periodic only) */
} sc_cloud;

typedef enum { SC_MOB_NONE, SC_MOB_CONSTANT, SC_MOB_EXPR, SC_MOB_SPE10 } sc_mobility_type;

typedef struct {
    sc_mobility_type type;
    double value;            /* constant                                                       */
    char *expr[3];           /* expression: expr[0] scalar, or one per axis (diagonal tensor)  */
    int ncomp;               /* 1 (scalar) or dim (diagonal)                                   */
    char *file;              /* SPE10: permx.geos or perm.txt, resolved against the folder     */
    int layer, i0, j0;       /* SPE10 layer and the sub-block's first cell                     */
} sc_mobility;

typedef struct {
    char *scheme;            /* a registered scheme name                                       */
    int kernel;              /* pst_kernel, or -1 for the scheme's default                      */
    int gradient;            /* pst_gradient (LV family)                                       */
    int variant;
    double cond_max, rank_tol, min_pair_distance;
    int mobility_mean;       /* pst_mobility_mean                                              */
    int on_degenerate;       /* pst_on_degenerate                                              */
} sc_operator;

typedef enum {
    SC_TASK_LAPLACIAN,       /* L u with no mobility: the Laplacian                             */
    SC_TASK_DIVERGENCE,      /* L u with the scene's mobility: div(M grad u)                   */
    SC_TASK_GRADIENT,
    SC_TASK_HESSIAN,
    SC_TASK_INTERPOLATE,     /* value (and Laplacian) at the points of a CSV file or a lattice  */
    SC_TASK_SOLVE,           /* L u = rhs with the boundary groups below                        */
    SC_TASK_DIFFUSE          /* du/dt = L u + source, stepped in time (docs/time-stepping.md)   */
} sc_task_type;

/* tasks[].operator of a solve or diffuse task: how it applies L. The plan's choice
 * (pst_plan.task_stored) is one of the last three. */
typedef enum {
    SC_OPERATOR_AUTO = -1,      /* the planner decides: stored in double where it fits      */
    SC_OPERATOR_MATRIX_FREE = 0,
    SC_OPERATOR_STORED = 1,      /* the weights stored in double (pst_op_store)             */
    SC_OPERATOR_STORED_FLOAT = 2 /* ... in float (pst_op_store_with, PST_STORE_FLOAT)      */
} sc_operator_use;

/* tasks[].method of a diffuse task: the theta of the theta-method is 0, 1 and 1/2. */
typedef enum { SC_METHOD_EXPLICIT, SC_METHOD_IMPLICIT, SC_METHOD_CRANK_NICOLSON } sc_method;

typedef enum { SC_NORM_REL_L2, SC_NORM_QSFDI11, SC_NORM_QSFDI11_NORMALISED, SC_NORM_LV78,
               SC_NORM_LV95, SC_NORM_MAX_ABS, SC_NORM_MAX_REL, SC_NNORMS } sc_norm;

typedef enum { SC_REGION_INTERIOR, SC_REGION_ALL, SC_REGION_BOX } sc_region_type;

typedef enum { SC_SIDE_ALL, SC_SIDE_XLO, SC_SIDE_XHI, SC_SIDE_YLO, SC_SIDE_YHI, SC_SIDE_ZLO,
               SC_SIDE_ZHI } sc_side;

/* Which of the cloud's own kinds a boundary group may claim. */
typedef enum { SC_GKIND_BOUNDARY, SC_GKIND_DIRICHLET, SC_GKIND_NEUMANN, SC_GKIND_INTERIOR,
               SC_GKIND_ANY } sc_group_kind;

/* A boundary group's region: a box, a ball, a half-space or where an expression is > 0. */
typedef enum { SC_SHAPE_NONE, SC_SHAPE_BOX, SC_SHAPE_SPHERE, SC_SHAPE_HALF_SPACE,
               SC_SHAPE_EXPR } sc_shape_type;

typedef struct {
    sc_shape_type type;
    double a[3], b[3];       /* box: lo, hi; sphere: centre; half-space: point, normal          */
    double radius;           /* sphere                                                          */
    char *expr;              /* expression                                                      */
} sc_shape;

/* Where a Neumann group's normals come from. */
typedef enum { SC_NORMALS_FILE, SC_NORMALS_FACE, SC_NORMALS_ESTIMATE } sc_normals;

typedef struct {
    sc_side where;           /* particles whose nearest box side is this one (or any)          */
    sc_group_kind kind;      /* of the cloud's kinds, the ones this group may claim            */
    sc_shape region;         /* and only inside this region (SC_SHAPE_NONE: anywhere)          */
    sc_normals normals;      /* Neumann: the cloud's normals, the box face's, or estimated      */
    int neumann;             /* 0: Dirichlet u = value; 1: Neumann du/dn = value               */
    char *value;             /* expression                                                     */
} sc_group;

typedef struct {
    char *name;              /* output field name (default: the type, made unique)             */
    sc_task_type type;
    char *field;             /* the input field (not for solve)                                */
    char *exact[6];          /* exact result expressions: 1 (scalar), dim (gradient), 3 / 6
                                (Hessian xx,yy,xy / xx,yy,zz,xy,xz,yz); NULL when not given     */
    int nexact;
    /* interpolate: points from a CSV file (x,y[,z] columns) or a lattice box */
    char *points_file;
    double points_lo[3], points_hi[3], points_spacing;
    /* solve */
    char *rhs;               /* expression                                                     */
    sc_group groups[SC_MAX_GROUPS];
    int ngroups;             /* 0: every boundary particle is Dirichlet with u = exact          */
    int solver, amg_source, restart, max_iter;
    int precond;             /* a pst_precond, or SC_PRECOND_AUTO (the planner decides)         */
    double amg_radius, amg_strong;
    int amg_aggressive, amg_coarsen, amg_interp, amg_pmax; /* pst_solve_opts' fields       */
    double rtol;
    char *petsc;             /* PETSc options: the solve runs in PETSc's KSP; NULL: not given   */
    int stored;              /* tasks[].operator: an sc_operator_use                            */
    /* diffuse: expressions of x, y, z and t (the boundary value NULL: the exact solution's) */
    char *initial, *source, *boundary_value;
    char *velocity[3];       /* dim expressions; nvelocity 0: the particles stay             */
    int nvelocity;
    sc_method method;
    double t_end, dt;        /* dt 0: not given (explicit: safety * the step limit)         */
    double safety, skin;     /* skin: the Verlet skin of moving particles, in h              */
    int max_steps, output_every;
    char *pvd, *steps_csv;   /* the time series and the per-step table (NULL: not written)   */
    /* errors */
    int norms[SC_MAX_NORMS];
    int nnorms;
    sc_region_type region;
    double region_lo[3], region_hi[3];
} sc_task;

typedef struct {
    char *name;
    char *expr;
} sc_field;

typedef struct {
    char *csv, *vtu, *report; /* output paths (NULL: not written), relative to the working dir */
    char *fields[SC_MAX_FIELDS];
    int nfields;             /* 0: every field                                                  */
    int vtu_compress;        /* zlib-compressed vtu arrays                                      */
} sc_outputs;

typedef struct {
    char *path;              /* the scene file ("(built-in)" for the default scene)           */
    char *dir;               /* its folder: relative input paths are resolved against it       */
    char *title;
    int dim;
    sc_cloud cloud;
    sc_mobility mobility;
    sc_operator op;
    sc_field fields[SC_MAX_FIELDS];
    int nfields;
    sc_task tasks[SC_MAX_TASKS];
    int ntasks;
    sc_outputs out;
    double memory_fraction;  /* refuse a plan above this fraction of the machine's memory      */
} pst_scene;

/* Read and check a scene. `text` is the file's content (or the built-in scene's), `path`
 * names it in messages. Overrides are "key=value" strings with dotted keys
 * ("cloud.jitter=0.3", "tasks.0.rtol=1e-8") applied before the checks. On failure returns
 * PST_EINPUT (or PST_ENOMEM) with "PATH:LINE:COLUMN: key 'cloud.jiter': unknown key (did you
 * mean 'cloud.jitter'?)"-style messages in err. */
int pst_scene_parse(pst_scene *s, const char *text, const char *path, const char *const *overrides,
                    int noverrides, char *err, size_t errlen);
/* Read a scene file and parse it (PST_EIO when the file cannot be read). */
int pst_scene_load(pst_scene *s, const char *path, const char *const *overrides, int noverrides,
                   char *err, size_t errlen);
/* The built-in default scene (scenes/default.json, compiled in). */
int pst_scene_default(pst_scene *s, const char *const *overrides, int noverrides, char *err,
                      size_t errlen);
void pst_scene_free(pst_scene *s);

/* Compile every expression of the scene (fields, mobility, exact values, right-hand sides,
 * boundary values) and discard it: PST_EINPUT with the message the run would give ("PATH:
 * KEY: WHY") for the first that does not compile. The planner calls it, so that a plan refuses
 * what the run would refuse. */
int pst_scene_compile_exprs(const pst_scene *s, char *err, size_t errlen);

/* The parameter table as help text (`pstencil help scene`) or as the markdown of
 * docs/scenes.md. */
void pst_scene_print_help(FILE *f, int markdown);

/* ---- The parameter table (scene_params.c): every key a scene may hold, declared once. The
 * loader checks scenes against it, the help text and docs/scenes.md are printed from it. ---- */

typedef enum {
    SC_T_INT,       /* a whole number                                                       */
    SC_T_REAL,      /* a finite number                                                      */
    SC_T_BOOL,
    SC_T_STRING,
    SC_T_ENUM,      /* a string among `values` (NULL values: a registered scheme name)       */
    SC_T_EXPR,      /* an expression: a non-empty string, compiled by the runner            */
    SC_T_EXPRS,     /* an expression or a list of expressions                               */
    SC_T_VEC,       /* a list of dim numbers                                                */
    SC_T_PATH,      /* a file name                                                          */
    SC_T_OBJECT,
    SC_T_LIST,      /* a list of `item`                                                     */
    SC_T_ENUM_OR_OBJECT, /* a string among `values`, or an object of the keys below it       */
    SC_T_AXES       /* true / false for every axis, or a list of dim booleans               */
} sc_type;

enum { SC_F_REQUIRED = 1, /* must be given (where it applies)                               */
       SC_F_SELECTOR = 2  /* its value decides which sibling keys apply (`applies`)         */ };

typedef struct {
    const char *key;     /* dotted path: "cloud.spacing", "tasks[].rtol" (an item of a list),
                            "fields.<name>" (any name in a map)                             */
    sc_type type;
    sc_type item;        /* SC_T_LIST: the type of an item                                  */
    const char *values;  /* "a|b|c": an enum's values, or the values an integer may take   */
    const char *def;     /* the default as JSON text (a vector's: one number for every
                            axis); NULL for none                                          */
    const char *units;   /* NULL for none                                                   */
    char lo_kind;        /* lower bound of a number (of a list's or object's length): '['
                            inclusive, '(' exclusive, 0 for none                           */
    double lo, hi;
    char hi_kind;        /* upper bound: ']' inclusive, ')' exclusive, 0 for none           */
    const char *applies; /* "a|b": the values of the sibling selector for which the key
                            applies (e.g. tasks[].rtol: "solve"); NULL: always           */
    int flags;           /* SC_F_*                                                          */
    const char *doc;     /* one sentence                                                    */
} sc_param;

extern const sc_param sc_params[];
extern const int sc_nparams;

/* The table entry of a table path ("tasks[].rtol"), or NULL. */
const sc_param *sc_param_find(const char *key);

/* The word of words[0..n) nearest to a misspelt `word` when it is a likely typo ("did you
 * mean"), else NULL. */
const char *sc_suggest_word(const char *word, const char *const *words, int n);

/* The number of periodic axes of the scene's cloud (cloud.periodic). */
int pst_scene_periodic_axes(const pst_scene *s);

/* The complete example scene of docs/scenes.md (the tests check that it loads). */
const char *pst_scene_example(void);

#endif
