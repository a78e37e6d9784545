/* Progress lines for long phases of a run (neighbours, precompute, solve iterations): drawn on
 * stderr only when it is a terminal and the run is not --quiet, so logs and pipes stay clean. */
#ifndef PSTENCIL_PROGRESS_H
#define PSTENCIL_PROGRESS_H

typedef struct {
    int enabled;
    const char *label;
    double t0, last_draw;
} cli_progress;

/* Start a phase; `enabled` is the caller's wish (not --quiet), the terminal test is made here. */
void progress_begin(cli_progress *p, int enabled, const char *label);
/* Redraw (at most ten times a second): a bar when 0 <= fraction <= 1, else only the clock. */
void progress_update(cli_progress *p, double fraction, const char *detail);
/* Finish the phase: clear the line. */
void progress_end(cli_progress *p);

#endif
