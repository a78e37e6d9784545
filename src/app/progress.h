/* Progress lines for the long phases of a run (neighbours, precompute, every task, solve
 * iterations, sweeps) on stderr: on a terminal one line redrawn in place, fitted to its width
 * and cleared at the end, unless --quiet; with --progress also when stderr is not a terminal
 * (a log), as whole lines at most once a second and one at the end of each phase. A phase of
 * a quiet run (--quiet, a sweep's runs) shows nothing either way.
 * docs/cli.md, "Progress". */
#ifndef PSTENCIL_PROGRESS_H
#define PSTENCIL_PROGRESS_H

#include "pstencil.h"

#include <stdatomic.h>
#include <stddef.h>

typedef struct {
    int mode;          /* PROGRESS_OFF, _TERMINAL or _LOG (progress.c) */
    const char *label; /* "neighbours", "precompute", "task grad", ... */
    const char *unit;  /* what the rate counts ("rows"), or NULL for no rate */
    double t0;
    /* microseconds after t0 of the last draw, -1 before the first: drawing threads claim a
     * draw with a compare-and-swap, so none waits on the terminal */
    _Atomic long long last_us;
    /* the latest state, for the line a log gets at the end of the phase */
    double fraction, rate;
    char detail[128];
} cli_progress;

/* --progress: show progress lines also when stderr is not a terminal. */
void progress_force(void);

/* Start a phase: `enabled` is the caller's wish (not --quiet), the terminal test is made here;
 * `unit` names what progress_count counts (NULL: progress_update's callers give no rate). */
void progress_begin(cli_progress *p, int enabled, const char *label, const char *unit);
/* Redraw when due (ten times a second on a terminal, once a second in a log): a bar and a
 * percentage when 0 <= fraction <= 1, else only the clock; detail goes at the end. */
void progress_update(cli_progress *p, double fraction, const char *detail);
/* The same with `done` of `total` units: the fraction and the rate in p's unit. */
void progress_count(cli_progress *p, uint64_t done, uint64_t total);
/* A library progress hook (pst_progress) that reports to p through progress_count; it may be
 * called from any of the library's threads. */
pst_progress progress_hook(cli_progress *p);
/* The hook for pst_nlist_build_with, whose work is two passes over the particles (count and
 * fill): shown as particles, so that the rate is in rows. */
pst_progress progress_list_hook(cli_progress *p);
/* Finish the phase: clear the terminal line, or write the phase's last line to the log. */
void progress_end(cli_progress *p);

/* The progress line of a phase, fitted into width - 1 columns (so that it never wraps) and at
 * most cap - 1 bytes, into out: "label [####....]  42% 12.3 s 1.2e5 rows/s detail". A bar and
 * percentage only for 0 <= fraction <= 1, the rate only for a unit and rate > 0. What does not
 * fit goes in this order: the bar shrinks (to 10), then goes; the detail is cut, then goes;
 * then the rate, then the clock; the rest is cut. Returns the columns used. */
size_t progress_format(char *out, size_t cap, int width, const char *label, double fraction,
                       double elapsed, double rate, const char *unit, const char *detail);

/* The width of the terminal on stderr (TIOCGWINSZ), else $COLUMNS, else 80. */
int progress_width(void);

#endif
