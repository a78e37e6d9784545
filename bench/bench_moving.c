/* Moving particles (bench/README.md, "bench_moving"): the neighbour list of a cloud moved by a
 * smooth velocity field, rebuilt every step against kept by pst_nlist_update with a skin, in
 * one run.
 *
 * The cloud: bench_poisson_cloud (jittered lattice on the unit box, K = 0.3, h = 1.2 s0),
 * Morton-sorted with cells of the list's radius. The field: a smooth swirl scaled so that no particle moves more than
 * `--move` s0 in a step (default 0.1). Per repetition, for the rebuild and for
 * each skin in turn (alternated, each from the same start), `--steps` steps of: move,
 * then the list (pst_nlist_build, or pst_nlist_update), then the scheme's operator on it
 * (pst_op_create every step, or created at the first step and pst_op_refresh after).
 * Printed: medians over the repetitions of the list's and the precompute's time per step, the
 * steps per second, the updates' rebuilds, and the list's speed-up over the rebuild.
 *
 * usage: bench_moving [--dim 2|3] [--n N] [--scheme S] [--steps S] [--move M] [--reps R]
 *                     [--skins a,b,..]
 * Defaults: 3, 1000000, qsfdi, 10, 0.1, 3, 0.2,0.4,0.6 (units of h). */
#include "bench_common.h"
#include "peak.h"
#include "pstencil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXSKINS 6
#define MAXREPS 15

typedef struct {
    int dim, steps, reps, nskins;
    size_t n;
    double move, skins[MAXSKINS];
    const char *scheme;
} args;

static int parse(int argc, char **argv, args *a)
{
    *a = (args){.dim = 3, .steps = 10, .reps = 3, .nskins = 3, .n = 1000000, .move = 0.1,
                .skins = {0.2, 0.4, 0.6}, .scheme = "qsfdi"};
    for (int i = 1; i < argc; i += 2) {
        const char *v = i + 1 < argc ? argv[i + 1] : "";
        if (strcmp(argv[i], "--dim") == 0)
            a->dim = atoi(v);
        else if (strcmp(argv[i], "--n") == 0)
            a->n = (size_t)atof(v);
        else if (strcmp(argv[i], "--scheme") == 0)
            a->scheme = v;
        else if (strcmp(argv[i], "--steps") == 0)
            a->steps = atoi(v);
        else if (strcmp(argv[i], "--move") == 0)
            a->move = atof(v);
        else if (strcmp(argv[i], "--reps") == 0)
            a->reps = atoi(v);
        else if (strcmp(argv[i], "--skins") == 0) {
            a->nskins = 0;
            for (const char *p = v; *p && a->nskins < MAXSKINS;
                 p = strchr(p, ',') ? strchr(p, ',') + 1 : "")
                a->skins[a->nskins++] = atof(p);
        } else {
            fprintf(stderr, "bench_moving: unknown option %s\n", argv[i]);
            return -1;
        }
    }
    if ((a->dim != 2 && a->dim != 3) || a->reps < 1 || a->reps > MAXREPS || a->steps < 1 ||
        a->steps > 10000 || !(a->move > 0 && a->move < 10) || a->nskins < 1 || a->n < 1000 ||
        a->n > 100000000) {
        fprintf(stderr, "bench_moving: --dim 2|3, --reps 1..%d, --steps 1..10000, --move in "
                        "(0, 10), --skins a,b,.. (up to %d), --n 1000..1e8\n",
                MAXREPS, MAXSKINS);
        return -1;
    }
    return 0;
}

/* One step of the swirl v = (sin(pi x) cos(pi y), -cos(pi x) sin(pi y), sin(pi x) cos(pi z)
 * / 2): each particle moves by dt v(x), dt = step (2D, |v| <= 1) or step / 1.5 (3D,
 * |v| <= 1.12), so by at most `step`. */
static void move(pst_cloud *c, double step)
{
    int dim = pst_cloud_dim(c);
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1);
    double *z = dim == 3 ? pst_cloud_coord(c, 2) : NULL;
    const double pi = 3.14159265358979323846, dt = step / (dim == 3 ? 1.5 : 1.0);
    size_t n = pst_cloud_size(c);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; ++i) {
        double sx = sin(pi * x[i]), cx = cos(pi * x[i]);
        double vx = sx * cos(pi * y[i]), vy = -cx * sin(pi * y[i]);
        if (z)
            z[i] += dt * 0.5 * sx * cos(pi * z[i]);
        x[i] += dt * vx;
        y[i] += dt * vy;
    }
}

typedef struct {
    double list, pre; /* seconds per step */
    uint64_t rebuilds;
} result;

/* `steps` steps from the start with the list rebuilt (skin < 0) or updated. Each run makes its
 * cloud afresh, Morton-sorted with cells of its own list's radius (the build sorts no rows
 * then: docs/neighbours.md), untimed. */
static int run(const args *a, double s0, double skin, result *r)
{
    double support = pst_kernel_support(pst_scheme_default_kernel(a->scheme));
    pst_cloud *c = bench_poisson_cloud("bench_moving", a->dim, a->n, BENCH_H_RATIO);
    if (!c)
        return -1;
    pst_cloud_morton_sort(c, (support + (skin > 0 ? skin : 0)) * BENCH_H_RATIO * s0, NULL);
    char err[PST_ERRLEN] = "";
    pst_nlist *nl = NULL;
    if (skin >= 0 && pst_nlist_build_skin(&nl, c, support, skin, err) != PST_OK) {
        fprintf(stderr, "bench_moving: %s\n", err);
        pst_cloud_destroy(c);
        return -1;
    }
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = a->scheme;
    *r = (result){0};
    pst_nlist_update_info info = {0};
    pst_op *op = NULL;
    for (int s = 0; s < a->steps; ++s) {
        move(c, a->move * s0);
        double t0 = omp_get_wtime();
        int st;
        if (skin < 0) {
            pst_nlist_destroy(nl);
            st = pst_nlist_build(&nl, c, support, err);
        } else {
            st = pst_nlist_update(nl, c, &info, err);
        }
        double t1 = omp_get_wtime();
        if (st == PST_OK && (skin < 0 || !op)) {
            pst_op_destroy(op);
            op = NULL;
            st = pst_op_create(&op, c, nl, &oo, err);
        } else if (st == PST_OK) {
            st = pst_op_refresh(op, err);
        }
        double t2 = omp_get_wtime();
        if (st != PST_OK) {
            pst_op_destroy(op);
            fprintf(stderr, "bench_moving: %s\n", err);
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
            return -1;
        }
        r->list += (t1 - t0) / a->steps;
        r->pre += (t2 - t1) / a->steps;
    }
    r->rebuilds = skin < 0 ? (uint64_t)a->steps : info.rebuilds - 1; /* less the first build */
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    return 0;
}

int main(int argc, char **argv)
{
    args a;
    if (parse(argc, argv, &a) != 0)
        return 1;
    pstb_probes pr;
    pstb_probes_run(&pr);
    char line[2048];
    pstb_probes_line(&pr, line, sizeof line);
    double s0 = 1.0 / bench_side(a.n, a.dim);
    int nmode = a.nskins + 1; /* mode 0: rebuild every step */
    double list[MAXSKINS + 1][MAXREPS], pre[MAXSKINS + 1][MAXREPS];
    uint64_t rebuilds[MAXSKINS + 1] = {0};
    for (int rep = 0; rep < a.reps; ++rep)
        for (int m = 0; m < nmode; ++m) {
            result r;
            if (run(&a, s0, m == 0 ? -1 : a.skins[m - 1], &r) != 0)
                return 1;
            list[m][rep] = r.list;
            pre[m][rep] = r.pre;
            rebuilds[m] = r.rebuilds;
            fprintf(stderr, "bench_moving: repetition %d, mode %d done\n", rep + 1, m);
        }
    printf("%s\n\n## moving: %dD about %zu particles, %s, %d steps of at most %.2f s0, %d threads; "
           "medians of %d alternated repetitions\n\n",
           line, a.dim, a.n, a.scheme, a.steps, a.move, omp_get_max_threads(), a.reps);
    printf("| list | rebuilds | list s/step | precompute s/step | steps/s | list speed-up |\n"
           "|---|---|---|---|---|---|\n");
    double base = bench_median(list[0], a.reps);
    for (int m = 0; m < nmode; ++m) {
        double l = bench_median(list[m], a.reps), p = bench_median(pre[m], a.reps);
        char name[64];
        if (m == 0)
            snprintf(name, sizeof name, "rebuilt every step");
        else
            snprintf(name, sizeof name, "updated, skin %.2f h", a.skins[m - 1]);
        printf("| %s | %llu | %.4g | %.4g | %.3g | %.2f |\n", name,
               (unsigned long long)rebuilds[m], l, p, 1.0 / (l + p), base / l);
    }
    return 0;
}
