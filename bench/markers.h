/* likwid marker regions around the timed loops of bench_operators: built with
 * -DPSTENCIL_LIKWID=ON (Debian package likwid) and run under `likwid-perfctr -m`
 * (bench/README.md). Without the option the macros do nothing. The applies open their own
 * OpenMP regions on the same (pinned) threads, so a region is started and stopped on every
 * thread of a parallel region around the timed loop. */
#ifndef PSTENCIL_BENCH_MARKERS_H
#define PSTENCIL_BENCH_MARKERS_H

#ifdef PSTENCIL_LIKWID
#include <likwid-marker.h>
#include <stdlib.h>

static void pstb_markers_close(void) { LIKWID_MARKER_CLOSE; }

/* Once per process, before the first region. */
#define PSTB_MARKERS_INIT()                                                                     \
    do {                                                                                        \
        LIKWID_MARKER_INIT;                                                                     \
        atexit(pstb_markers_close);                                                             \
    } while (0)
#define PSTB_REGION_START(name)                                                                 \
    do {                                                                                        \
        _Pragma("omp parallel") LIKWID_MARKER_START(name);                                      \
    } while (0)
#define PSTB_REGION_STOP(name)                                                                  \
    do {                                                                                        \
        _Pragma("omp parallel") LIKWID_MARKER_STOP(name);                                       \
    } while (0)
#else
#define PSTB_MARKERS_INIT() ((void)0)
#define PSTB_REGION_START(name) ((void)(name))
#define PSTB_REGION_STOP(name) ((void)(name))
#endif

#endif
