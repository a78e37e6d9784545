/* Running a sweep's combinations: one in this process (sweep_run.c), or several at once in
 * worker processes (sweep_jobs.c, docs/sweeps.md "Runs at once"). Private to the sweep files. */
#ifndef PSTENCIL_SWEEP_JOBS_H
#define PSTENCIL_SWEEP_JOBS_H

#include "sweep.h"
#include "sweep_csv.h"

struct cJSON;

/* Run combination k in this process, quiet: the run's status (or the scene's parse status,
 * with *ran = 0), its report in *report (NULL when the run failed; cJSON_Delete it) and its
 * message in msg. */
int sweep_run_one(const pst_sweep *sw, const pst_sweep_opts *o, size_t k, int *ran,
                  struct cJSON **report, char *msg, size_t len);

/* Add combination k's rows from what sweep_run_one gave (failed rows when report is NULL)
 * and count it in stats. PST_ENOMEM or PST_OK. */
int sweep_record(sweep_rows *j, size_t k, int ran, const struct cJSON *report, int status,
                 const char *msg, pst_sweep_stats *stats);

/* sweep_run_one then sweep_record; PST_ENOMEM or PST_OK. */
int sweep_run_combo(const pst_sweep *sw, const pst_sweep_opts *o, sweep_rows *j, size_t k,
                    pst_sweep_stats *stats);

/* Rewrite the CSV (all or nothing) with the rows so far; "output.csv: ..." in err. */
int sweep_write_rows(const pst_sweep *sw, const sweep_rows *j, char *err, size_t errlen);

/* 1 when combination k is a small run, which may run beside jobs - 1 others in a worker: its
 * plan has at most 4e6 neighbour pairs (a cloud file at most 1 MB) and `jobs` of its memory
 * estimate fit. 0 for a large run, and for a scene that does not parse or plan (it fails in
 * this process, as it would alone). */
int sweep_combo_is_small(const pst_sweep *sw, size_t k, int jobs);

/* Every combination not done, with up to o->jobs small runs at once in worker processes
 * (o->worker_exe) and the large ones alone in this process with all threads; the CSV after
 * each run, rows in combination order whatever order the runs end in. PST_OK, or the status
 * of a CSV that cannot be written or of memory that ran out (err says). */
int sweep_run_jobs(const pst_sweep *sw, const pst_sweep_opts *o, sweep_rows *j,
                   const char *done, pst_sweep_stats *stats, char *err, size_t errlen);

/* A report's numbers as strings "pst:%.17g" and back: cJSON prints 15 digits when they
 * come within an epsilon, and null for NaN and infinities, so that a worker's report would not
 * give the cells the same report gives in this process. */
void sweep_report_encode(struct cJSON *report);
void sweep_report_decode(struct cJSON *report);

#endif
