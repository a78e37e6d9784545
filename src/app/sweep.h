/* Sweeps (docs/sweeps.md): a scene run over the Cartesian product of lists of key values, one
 * CSV row per (run, task) written all or nothing after every run, resumable, and a summary
 * JSON (means, standard deviations, convergence slopes) computed from the CSV alone. The
 * front end's interface: the sweep file (sweep_file.c), its grid (sweep_grid.c), the runs
 * (sweep_run.c), the CSV (sweep_csv.c) and the summary (sweep_summary.c). */
#ifndef PSTENCIL_SWEEP_H
#define PSTENCIL_SWEEP_H

#include "pstencil.h"

#include <stddef.h>

struct cJSON;

enum { SW_MAX_KEYS = 16, SW_MAX_GRIDS = 16, SW_MAX_OVERRIDES = 64 };
/* The most combinations (runs) a sweep may have: a larger grid is refused when it is read,
 * its product counted without overflow (docs/sweeps.md). */
#define SW_MAX_COMBOS 100000

typedef struct {
    char *path;              /* the sweep file (messages)                                       */
    char *scene_text;        /* the scene: a file's text, or the inline object's text padded so
                                that its lines and columns are the sweep file's                */
    char *scene_path;        /* the name the scene is parsed under (its folder resolves inputs) */
    int nkeys;
    char *keys[SW_MAX_KEYS]; /* grid keys, in grid order (CSV columns)                          */
    int ngrids;              /* "grid" is one object (1) or a list of objects, the union of
                                their products; every object has the same keys in order        */
    int nvalues[SW_MAX_GRIDS][SW_MAX_KEYS];
    char **values[SW_MAX_GRIDS][SW_MAX_KEYS]; /* JSON text of each value                      */
    int noverrides;
    char *overrides[SW_MAX_OVERRIDES]; /* fixed "key=json" overrides                           */
    char *csv, *summary;     /* output paths, relative to the working directory                 */
    char *pvd;               /* a .pvd collecting each run's VTU, STEM_runK.vtu beside it (NULL:
                                the runs write no VTU)                                          */
    char *slope_key, *repeat_key;
    size_t ncombos;          /* runs in the whole sweep                                         */
} pst_sweep;

/* Read and check a sweep. `text` is the file's content, `path` names it in messages and
 * resolves a "scene" given as a file name. Errors (PST_EINPUT, PST_EIO for an unreadable
 * scene file, PST_ENOMEM) are "PATH:LINE:COLUMN: key 'grid.cloud.spaing': ..." in err. The
 * scene itself must parse with the fixed overrides. */
int pst_sweep_parse(pst_sweep *sw, const char *text, const char *path, char *err,
                    size_t errlen);
int pst_sweep_load(pst_sweep *sw, const char *path, char *err, size_t errlen);
void pst_sweep_free(pst_sweep *sw);

/* The grid values of combination k (0 <= k < ncombos) as JSON texts (nkeys of them), in the
 * order of the runs: grid after grid, the last key fastest. */
void pst_sweep_combo(const pst_sweep *sw, size_t k, const char *vals[SW_MAX_KEYS]);

/* Parse and plan every combination without running it (`pstencil sweep --plan`): PST_OK when
 * all do, else the first failure's status with "combination K (key=value ...): reason" in
 * err. *nfailed (may be NULL) counts the failing combinations. */
int pst_sweep_check(const pst_sweep *sw, size_t *nfailed, char *err, size_t errlen);

typedef struct {
    int resume;                   /* keep the runs of an existing CSV (ok or not-converged)    */
    int quiet;                    /* no progress bar                                           */
    const struct cJSON *machine;  /* members copied into the summary (NULL: none)             */
    int (*start_mpi)(void);       /* handed to every run (pst_run_opts.start_mpi)              */
    int (*start_petsc)(char *err); /* handed to every run (pst_run_opts.start_petsc)         */
    /* Runs at once (docs/sweeps.md): with jobs > 1 and a worker program, up to `jobs` small
     * runs at once, each in a worker process with pst_threads() / jobs threads, and large
     * runs one at a time in this process; otherwise every run here, one after the other. */
    int jobs;
    const char *worker_exe;       /* a pstencil program: `sweep PATH --worker DIGEST` serves
                                     runs (pst_sweep_serve); needs a sweep loaded from PATH */
} pst_sweep_opts;

typedef struct {
    long runs;                    /* scene runs made by this call                              */
    long in_workers;              /* of which in worker processes (runs at once)               */
    long skipped;                 /* combinations kept from the CSV (--resume)                 */
    long failed;                  /* combinations whose rows are failed                        */
    long not_converged;           /* combinations with a solve that did not converge           */
    long dropped;                 /* rows of the old CSV that match no combination (--resume)  */
    size_t rows;                  /* CSV rows written                                          */
} pst_sweep_stats;

/* Run the sweep: every combination (or those --resume does not keep), the CSV after each, the
 * summary at the end. PST_OK when the files are written, whatever the runs did (stats says);
 * PST_EIO / PST_EINPUT (a CSV whose header differs, on resume) with the reason in err. */
int pst_sweep_run(const pst_sweep *sw, const pst_sweep_opts *o, pst_sweep_stats *stats,
                  char *err, size_t errlen);

/* A sweep worker: check `digest` (the parent's digest of the sweep, as sweep_jobs.c passes
 * it) against sw, then run every combination K sent as "K\n" on socket fd and answer each
 * with one line of JSON, until the input ends (PST_OK). PST_EINPUT for another sweep or a bad
 * line, PST_EIO when the parent is gone, PST_ENOMEM; the reason in err. */
int pst_sweep_serve(const pst_sweep *sw, const char *digest, const pst_sweep_opts *o, int fd,
                    char *err, size_t errlen);

/* The CSV's columns after the grid keys. */
extern const char *const pst_sweep_columns[];
extern const int pst_sweep_ncolumns;

/* Mean and sample standard deviation (n - 1; NAN for one value) of v[0..n), n >= 1, two-pass
 * for accuracy: the sweep summary's and the plots' error bars. */
void pst_mean_std(const double *v, size_t n, double *mean, double *sd);

/* The summary of a sweep CSV (a table from pst_csv_read_table): groups (grid keys except
 * repeat_key, per task: counts, means and standard deviations of the norms and times, mean
 * iterations) and convergence fits (grid keys except slope_key and repeat_key, per task and
 * norm: least-squares slope of log(mean norm) against log(slope_key), its standard error, the
 * points). The statistics read the table's numbers (t->num), the groups its key cells. A
 * function of the table alone; NULL when out of memory or when the header is not a sweep's.
 * cJSON_Delete it. */
struct cJSON *pst_sweep_summary(const pst_csv_table *t, const char *slope_key,
                                const char *repeat_key);

#endif
