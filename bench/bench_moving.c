/* Moving particles (bench/README.md, "bench_moving"): the neighbour list of a cloud moved by a
 * smooth velocity field, rebuilt every step against kept by pst_nlist_update with a skin, in
 * one run; with --solve, a Poisson solve per step (the pressure solve of an incompressible
 * particle method) whose handle is created every step or refreshed (pst_krylov_refresh).
 *
 * The cloud: bench_poisson_cloud (jittered lattice on the unit box, K = 0.3, h = 1.2 s0),
 * Morton-sorted with cells of the list's radius. The field: a smooth swirl scaled so that no particle moves more than
 * `--move` s0 in a step (default 0.1). Per repetition, for the rebuild and for
 * each skin in turn (alternated, each from the same start), `--steps` steps of: move,
 * then the list (pst_nlist_build, or pst_nlist_update), then the scheme's operator on it
 * (pst_op_create every step, or created at the first step and pst_op_refresh after), then
 * with --solve the manufactured problem's solve (GMRES, the given preconditioner; the handle
 * created every step in the rebuild mode, created at the first step and refreshed after in the
 * update modes, which keep an AMG hierarchy by the amg_reuse rule).
 * Printed: medians over the repetitions of the list's, the precompute's and the solve's time
 * per step, the steps per second, the updates' rebuilds, the list's speed-up over the rebuild,
 * and the solves' iterations and preconditioner set-ups.
 *
 * usage: bench_moving [--dim 2|3] [--n N] [--scheme S] [--steps S] [--move M] [--reps R]
 *                     [--skins a,b,..] [--solve none|jacobi|amg]
 * Defaults: 3, 1000000, qsfdi, 10, 0.1, 3, 0.2,0.4,0.6 (units of h), none. */
#include "bench_common.h"
#include "peak.h"
#include "pstencil.h"
#include "support.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAXSKINS 6
#define MAXREPS 15

typedef struct {
    int dim, steps, reps, nskins;
    int solve; /* -1: none, else the pst_precond of the solves */
    size_t n;
    double move, skins[MAXSKINS];
    const char *scheme;
} args;

static int parse(int argc, char **argv, args *a)
{
    *a = (args){.dim = 3, .steps = 10, .reps = 3, .nskins = 3, .solve = -1, .n = 1000000,
                .move = 0.1, .skins = {0.2, 0.4, 0.6}, .scheme = "qsfdi"};
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
        } else if (strcmp(argv[i], "--solve") == 0) {
            a->solve = strcmp(v, "none") == 0     ? -1
                       : strcmp(v, "jacobi") == 0 ? PST_PREC_JACOBI
                       : strcmp(v, "amg") == 0    ? PST_PREC_AMG
                                                  : -2;
        } else {
            fprintf(stderr, "bench_moving: unknown option %s\n", argv[i]);
            return -1;
        }
    }
    if ((a->dim != 2 && a->dim != 3) || a->reps < 1 || a->reps > MAXREPS || a->steps < 1 ||
        a->steps > 10000 || !(a->move > 0 && a->move < 10) || a->nskins < 1 || a->n < 1000 ||
        a->n > 100000000 || a->solve == -2 || (a->solve == PST_PREC_AMG && !pst_have_amg())) {
        fprintf(stderr, "bench_moving: --dim 2|3, --reps 1..%d, --steps 1..10000, --move in "
                        "(0, 10), --skins a,b,.. (up to %d), --n 1000..1e8, --solve none|jacobi|"
                        "amg (amg: a build with hypre)\n",
                MAXREPS, MAXSKINS);
        return -1;
    }
    if (pst_scheme_default_kernel(a->scheme) == PST_KERNEL_UNKNOWN) {
        fprintf(stderr, "bench_moving: unknown scheme '%s'\n", a->scheme);
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
    double list, pre, solve; /* seconds per step */
    double iterations;       /* per solve */
    int setups;              /* preconditioner set-ups over the steps */
    uint64_t rebuilds;
} result;

/* Destroy a solver handle, counting its preconditioner set-ups. */
static void drop_solver(pst_krylov **kr, result *r)
{
    pst_krylov_stats ks;
    pst_krylov_get_stats(*kr, &ks);
    r->setups += ks.precond_setups;
    pst_krylov_destroy(*kr);
    *kr = NULL;
}

/* The step's solve: the handle created (none yet) or refreshed, then one solve of the
 * manufactured problem from u = 0. */
static int solve_step(const args *a, const pst_cloud *c, pst_op *op, pst_krylov **kr,
                      result *r, char *err)
{
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = PST_SOLVER_GMRES;
    so.precond = (pst_precond)a->solve;
    int st = *kr ? pst_krylov_refresh(*kr, err) : pst_krylov_create(kr, op, &so, err);
    size_t n = pst_cloud_size(c);
    double *b = malloc(n * sizeof *b), *ue = malloc(n * sizeof *ue), *u = calloc(n, sizeof *u);
    pst_solve_result res;
    if (st == PST_OK && b && ue && u) {
        bench_poisson_rhs(c, b, ue);
        st = pst_krylov_solve(*kr, b, u, &res, err);
        r->iterations += (double)res.iterations / a->steps;
    }
    free(b);
    free(ue);
    free(u);
    return st;
}

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
    pst_krylov *kr = NULL;
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
            drop_solver(&kr, r); /* the rebuild mode's solver goes with its operator */
            pst_op_destroy(op);
            op = NULL;
            st = pst_op_create(&op, c, nl, &oo, err);
        } else if (st == PST_OK) {
            st = pst_op_refresh(op, err);
        }
        double t2 = omp_get_wtime();
        if (st == PST_OK && a->solve >= 0)
            st = solve_step(a, c, op, &kr, r, err);
        double t3 = omp_get_wtime();
        if (st != PST_OK) {
            pst_krylov_destroy(kr);
            pst_op_destroy(op);
            fprintf(stderr, "bench_moving: %s\n", err);
            pst_nlist_destroy(nl);
            pst_cloud_destroy(c);
            return -1;
        }
        r->list += (t1 - t0) / a->steps;
        r->pre += (t2 - t1) / a->steps;
        r->solve += (t3 - t2) / a->steps;
    }
    r->rebuilds = skin < 0 ? (uint64_t)a->steps : info.rebuilds - 1; /* less the first build */
    drop_solver(&kr, r);
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
    if (a.solve == PST_PREC_AMG)
        test_mpi_init();
    pstb_probes pr;
    pstb_probes_run(&pr);
    char line[2048];
    pstb_probes_line(&pr, line, sizeof line);
    double s0 = 1.0 / bench_side(a.n, a.dim);
    int nmode = a.nskins + 1; /* mode 0: rebuild every step */
    double list[MAXSKINS + 1][MAXREPS], pre[MAXSKINS + 1][MAXREPS], sol[MAXSKINS + 1][MAXREPS];
    result last[MAXSKINS + 1];
    for (int rep = 0; rep < a.reps; ++rep)
        for (int m = 0; m < nmode; ++m) {
            if (run(&a, s0, m == 0 ? -1 : a.skins[m - 1], &last[m]) != 0)
                return 1;
            list[m][rep] = last[m].list;
            pre[m][rep] = last[m].pre;
            sol[m][rep] = last[m].solve;
            fprintf(stderr, "bench_moving: repetition %d, mode %d done\n", rep + 1, m);
        }
    static const char *const prec[] = {"none", "Jacobi", "AMG"};
    printf("%s\n\n## moving: %dD about %zu particles, %s, %d steps of at most %.2f s0, %d threads; "
           "medians of %d alternated repetitions",
           line, a.dim, a.n, a.scheme, a.steps, a.move, omp_get_max_threads(), a.reps);
    if (a.solve >= 0)
        printf("; a GMRES + %s solve per step", prec[a.solve]);
    printf("\n\n| list | rebuilds | list s/step | precompute s/step |%s steps/s | list speed-up |\n"
           "|---|---|---|---|%s---|---|\n",
           a.solve >= 0 ? " solve s/step | iterations | set-ups |" : "",
           a.solve >= 0 ? "---|---|---|" : "");
    double base = bench_median(list[0], a.reps);
    for (int m = 0; m < nmode; ++m) {
        double l = bench_median(list[m], a.reps), p = bench_median(pre[m], a.reps);
        double q = bench_median(sol[m], a.reps);
        char name[64], solve[128] = "";
        if (m == 0)
            snprintf(name, sizeof name, "rebuilt every step");
        else
            snprintf(name, sizeof name, "updated, skin %.2f h", a.skins[m - 1]);
        if (a.solve >= 0) /* iterations and set-ups: the last repetition's (deterministic) */
            snprintf(solve, sizeof solve, " %.4g | %.1f | %d |", q, last[m].iterations,
                     last[m].setups);
        printf("| %s | %llu | %.4g | %.4g |%s %.3g | %.2f |\n", name,
               (unsigned long long)last[m].rebuilds, l, p, solve, 1.0 / (l + p + q), base / l);
    }
    return 0;
}
