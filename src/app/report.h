/* The JSON report of a scene run and the run's output files (docs/running.md, "Outputs"). The
 * report is a cJSON tree the runner fills as it goes; every file is written all or nothing. */
#ifndef PSTENCIL_REPORT_H
#define PSTENCIL_REPORT_H

#include "plan.h"

#include <cjson/cJSON.h>
#include <stdio.h>

/* A new report: program version, threads, the scene's path and title. */
cJSON *report_begin(const pst_scene *s);
/* Wall-clock seconds of a run phase, under "timers". */
void report_timer(cJSON *report, const char *name, double seconds);
/* The process's peak resident memory so far (bytes), as "peak_rss_bytes". */
void report_peak_memory(cJSON *report);
/* An operator: scheme, kernel, its parameters, per-phase timers and row status counts, under
 * "operators". */
void report_operator(cJSON *report, const pst_op *op);
/* The parameters of an operator as a new JSON object: scheme, gradient, variant, mobility
 * mean, the degeneracy thresholds (cond_max, rank_tol, min_pair_distance), on_degenerate,
 * "regularisation":
 * "none" (degenerate rows are never regularised) and the scheme's fallback chain
 * (pst_scheme_fallback). Every result that names an operator carries them. */
cJSON *report_parameters(const pst_op_opts *oo);
/* A task's name and type. */
void report_task_header(cJSON *task, const sc_task *t);
/* A solve's outcome: solver, how it applied L (`stored`: pst_plan.task_stored), converged,
 * iterations, residual, message, residual history; fix_mean (the solve fixed the mean of u)
 * and, when it did, mean_shift (lambda). */
void report_solve(cJSON *task, const pst_solve_result *res, int stored, int fix_mean);
/* How a task applied L, by its plan's task_stored, in the scene's words (tasks[].operator):
 * "matrix_free", "stored" or "stored_float". */
const char *report_operator_use(int stored);
/* The plan's decisions and estimates, the counters and the cloud's size, at the end. */
void report_finish(cJSON *report, const pst_plan *p, const pst_run_counters *cnt,
                   const pst_cloud *c);
/* Write the scene's outputs: CSV and VTU of the cloud (only outputs.fields when given: a task's
 * name selects every field it added) and the JSON report. `status` (may be NULL): the row
 * status the VTU carries. Counts the files. */
int report_write_outputs(const pst_scene *s, const pst_cloud *c, const uint8_t *status,
                         cJSON *report, pst_run_counters *cnt, char *err, size_t errlen);
/* An interpolation task's values at its points: "<csv stem>_<task>.csv" beside outputs.csv
 * with columns x,y[,z],value,laplacian. */
int report_write_points(const char *csv, const char *task, int dim, double *const pts[3],
                        size_t m, const double *value, const double *lap, char *err,
                        size_t errlen);
/* A few human-readable lines: tasks, norms, solver outcomes, total time. */
void report_summary(FILE *f, const cJSON *report);

#endif
