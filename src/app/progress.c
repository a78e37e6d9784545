#define _POSIX_C_SOURCE 200809L /* fileno */

#include "progress.h"

#include <omp.h>
#include <stdio.h>
#include <unistd.h>

void progress_begin(cli_progress *p, int enabled, const char *label)
{
    p->enabled = enabled && isatty(fileno(stderr));
    p->label = label;
    p->t0 = omp_get_wtime();
    p->last_draw = -1;
    progress_update(p, -1, "");
}

void progress_update(cli_progress *p, double fraction, const char *detail)
{
    if (!p->enabled)
        return;
    double now = omp_get_wtime();
    if (p->last_draw >= 0 && now - p->last_draw < 0.1)
        return;
    p->last_draw = now;
    char bar[31] = "";
    if (fraction >= 0 && fraction <= 1) {
        int full = (int)(fraction * 30 + 0.5);
        for (int k = 0; k < 30; ++k)
            bar[k] = k < full ? '#' : '.';
        bar[30] = '\0';
    }
    fprintf(stderr, "\r\033[K%-12s %s%s%s %6.1f s %s", p->label, bar[0] ? "[" : "", bar,
            bar[0] ? "]" : "", now - p->t0, detail);
    fflush(stderr);
}

void progress_end(cli_progress *p)
{
    if (!p->enabled)
        return;
    fprintf(stderr, "\r\033[K");
    fflush(stderr);
}
