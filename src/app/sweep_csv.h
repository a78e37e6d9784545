/* The sweep CSV's rows (src/app/sweep_csv.c): built from a run's report or a failure, written
 * all or nothing, matched back to combinations on --resume. Private to the sweep files. */
#ifndef PSTENCIL_SWEEP_CSV_H
#define PSTENCIL_SWEEP_CSV_H

#include "scene.h"
#include "sweep.h"

#include <stdio.h>

struct cJSON;

/* Positions in pst_sweep_columns (after the grid keys). */
enum { C_DIM, C_PARTICLES, C_NEIGH, C_TASK, C_TYPE, C_NORM0, C_ITER = C_NORM0 + 7, C_CONV,
       C_RESID, C_T_CLOUD, C_T_NEIGH, C_T_GEOM, C_T_MOM, C_T_INV, C_T_W, C_T_PRE, C_T_TASK,
       C_T_TOTAL, C_CPU, C_RSS, C_MEM, C_ROWS0, C_STATUS = C_ROWS0 + 5, C_MESSAGE, C_N };

/* The seven norm columns from C_NORM0. */
extern const char *const sweep_norm_columns[7];

/* Rows of cells, ncols each (the grid keys, then the sweep columns). */
typedef struct {
    char **cells;
    size_t nrows, cap;
} sweep_rowset;

/* The rows of a whole sweep: per combination. */
typedef struct {
    const pst_sweep *sw;
    int ncols;
    sweep_rowset *runs;
    size_t ncombos;
} sweep_rows;

/* A new row of ncols NULL cells, or NULL when out of memory. */
char **sweep_new_row(sweep_rowset *rs, int ncols);
void sweep_rowset_clear(sweep_rowset *rs, int ncols);

/* The CSV cell of a grid value: a JSON string's text, anything else its compact JSON. */
char *sweep_key_cell(const char *json);

/* Rows of combination k from its run's report, or failed rows (one per scene task, or one)
 * when `report` is NULL, `s` (may be NULL) naming the tasks. PST_ENOMEM or PST_OK. */
int sweep_add_rows(sweep_rows *j, size_t k, const struct cJSON *report,
                   const pst_scene *s, const char *message);

/* The pst_write_atomic writer of the CSV: the header, then every combination's rows. */
void sweep_write_csv(FILE *f, const void *rows);

/* The rows as a table (copies), for the summary. */
int sweep_rows_table(const sweep_rows *j, pst_csv_table *t, char *err);

#endif
