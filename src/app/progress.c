/* Progress lines on stderr (progress.h): when to draw, and how (in place on a terminal, whole
 * lines in a log). The library's hooks call progress_count from its worker threads; a draw is
 * claimed with a compare-and-swap on the time of the last one, so no thread waits. */
#define _POSIX_C_SOURCE 200809L /* fileno */

#include "progress.h"

#include <omp.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

enum { PROGRESS_OFF, PROGRESS_TERMINAL, PROGRESS_LOG };

/* Set once by --progress, before any phase starts: a log gets the lines a terminal would. */
static int forced;

void progress_force(void) { forced = 1; }

void progress_begin(cli_progress *p, int enabled, const char *label, const char *unit)
{
    int tty = isatty(fileno(stderr));
    p->mode = !enabled ? PROGRESS_OFF
              : tty    ? PROGRESS_TERMINAL
              : forced ? PROGRESS_LOG
                       : PROGRESS_OFF;
    p->label = label;
    p->unit = unit;
    p->t0 = omp_get_wtime();
    atomic_init(&p->last_us, -1);
    p->fraction = -1;
    p->rate = 0;
    p->detail[0] = '\0';
    if (p->mode == PROGRESS_TERMINAL)
        progress_update(p, -1, ""); /* the label at once; a log waits a second */
}

static void draw(cli_progress *p, double elapsed)
{
    char line[512];
    progress_format(line, sizeof line, progress_width(), p->label, p->fraction, elapsed,
                    p->rate, p->unit, p->detail);
    if (p->mode == PROGRESS_TERMINAL)
        fprintf(stderr, "\r\033[K%s", line);
    else
        fprintf(stderr, "%s\n", line);
    fflush(stderr);
}

/* Claim the draw when the last one is older than the mode's interval (ten a second on a
 * terminal, one a second in a log): a terminal's first draw is due at once, a log's after a
 * second, so that a short phase writes only its last line. */
static int due(cli_progress *p, double elapsed)
{
    long long now = (long long)(elapsed * 1e6), last = atomic_load(&p->last_us);
    long long every = p->mode == PROGRESS_TERMINAL ? 100000 : 1000000;
    long long since = last >= 0 ? now - last : p->mode == PROGRESS_LOG ? now : every;
    return since >= every && atomic_compare_exchange_strong(&p->last_us, &last, now);
}

void progress_update(cli_progress *p, double fraction, const char *detail)
{
    if (p->mode == PROGRESS_OFF)
        return;
    double elapsed = omp_get_wtime() - p->t0;
    p->fraction = fraction;
    snprintf(p->detail, sizeof p->detail, "%s", detail ? detail : "");
    if (due(p, elapsed))
        draw(p, elapsed);
}

void progress_count(cli_progress *p, uint64_t done, uint64_t total)
{
    if (p->mode == PROGRESS_OFF)
        return;
    double elapsed = omp_get_wtime() - p->t0;
    p->fraction = total ? (double)done / (double)total : 1.0;
    p->rate = elapsed > 0 ? (double)done / elapsed : 0;
    if (due(p, elapsed))
        draw(p, elapsed);
}

static void hook(void *user, uint64_t done, uint64_t total) { progress_count(user, done, total); }

pst_progress progress_hook(cli_progress *p) { return (pst_progress){hook, p}; }

static void list_hook(void *user, uint64_t done, uint64_t total)
{
    progress_count(user, done / 2, total / 2);
}

pst_progress progress_list_hook(cli_progress *p) { return (pst_progress){list_hook, p}; }

void progress_end(cli_progress *p)
{
    if (p->mode == PROGRESS_TERMINAL) {
        fprintf(stderr, "\r\033[K");
        fflush(stderr);
    } else if (p->mode == PROGRESS_LOG) {
        draw(p, omp_get_wtime() - p->t0);
    }
}
