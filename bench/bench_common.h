/* The set-up the benchmark programs share: jittered lattices from the library's own generator. */
#ifndef PSTENCIL_BENCH_COMMON_H
#define PSTENCIL_BENCH_COMMON_H

#include "pstencil.h"

/* The 10^6-particle lattices of bench_neighbours and bench_operators: jitter K and h / s0. */
#define BENCH_JITTER 0.5
#define BENCH_H_RATIO 1.2

/* Options for the box [0, hi]^dim with spacing s0, jitter K (fraction of s0) and h = h_ratio s0;
 * every other option at its default (pst_lattice_defaults). */
pst_lattice_opts bench_box(int dim, double hi, double s0, double jitter, double h_ratio);

/* The lattice of o; NULL after the message "who: reason" on stderr. */
pst_cloud *bench_lattice(const char *who, const pst_lattice_opts *o);

/* 10^6 particles (1000^2 or 100^3) on a lattice of spacing 1 (V = 1, the lattice cell), all
 * interior, jitter BENCH_JITTER, h = BENCH_H_RATIO, seed 2024, lattice (input) order; NULL
 * after a message naming `who`. */
pst_cloud *bench_million(const char *who, int dim);

/* Spacings per side of a lattice of about n points: round(n^(1/dim)) - 1. */
int bench_side(size_t n, int dim);

/* The median of v[0..n) (n >= 1); v is sorted in place. */
double bench_median(double *v, int n);

/* The manufactured Poisson problem of bench_solve and bench_petsc (docs/solving.md): a jittered
 * lattice of about n particles on the unit square or cube, K = 0.3, h = h_ratio s0, with a
 * Dirichlet boundary layer; NULL after a message naming `who`. */
pst_cloud *bench_poisson_cloud(const char *who, int dim, size_t n, double h_ratio);

/* Its right-hand side and exact solution at every particle of c: ue = sin(6x + 8y) (2D) or
 * sin(2x + 3y + 4z) (3D), b = the exact Laplacian inside and ue on Dirichlet particles. */
void bench_poisson_rhs(const pst_cloud *c, double *b, double *ue);

/* Reset this process's resident-memory high-water mark to its current resident size (Linux
 * /proc/self/clear_refs), so that the next bench_memory("VmHWM") is the peak of what runs in
 * between. */
void bench_peak_reset(void);

/* A size line of /proc/self/status ("VmRSS", "VmHWM") in bytes; 0 when unreadable. */
double bench_memory(const char *key);

#endif
