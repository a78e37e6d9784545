/* The Lukyanov–Vuik boundary-value problems (§5.1, §5.2) and the SPE10 case; see lv_problems.h. */
#include "lv_problems.h"
#include "tpfa_ref.h"

#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define LV_PI 3.14159265358979323846

const double lv_psi[4] = {150.0, 90.0, 150.0, 200.0};

/* The side of a face particle from its outward normal: 0 (y = 0), 1 (x = L), 2 (y = H),
 * 3 (x = 0); -1 for an interior particle (normal 0). */
static int face_side(double nx, double ny)
{
    if (ny < -0.5)
        return 0;
    if (nx > 0.5)
        return 1;
    if (ny > 0.5)
        return 2;
    if (nx < -0.5)
        return 3;
    return -1;
}

/* sum over odd n of 4/(n pi) sin(n pi a) e^{-n pi b}, a in [0,1], b > 0, in closed form. */
static double odd_sine_exp(double a, double b)
{
    return 2.0 / LV_PI * atan2(sin(LV_PI * a), sinh(LV_PI * b));
}

/* One side's term of (96): sum over odd n of 4/(n pi) sin(n pi a) sinh(n pi (1-b))/sinh(n pi),
 * evaluated as the closed form of the e^{-n pi b} series plus the remainder
 * (e^{-n pi (2+b)} - e^{-n pi (2-b)}) / (1 - e^{-2 n pi}), which is below e^{-n pi} in size. */
static double side96(double a, double b, int nterms)
{
    double s = 0;
    if (nterms > 0) {
        /* the printed series, truncated: sinh ratio as e^{-n pi b}(1-e^{-2npi(1-b)})/(1-e^{-2npi}) */
        for (int k = 0; k < nterms; ++k) {
            double n = 2.0 * k + 1, q = n * LV_PI;
            double r = exp(-q * b) * (-expm1(-2 * q * (1 - b))) / (-expm1(-2 * q));
            s += 4.0 / q * sin(q * a) * r;
        }
        return s;
    }
    if (b <= 0)
        return (a > 0 && a < 1) ? 1.0 : 0.0;
    s = odd_sine_exp(a, b);
    for (int k = 0; k < 20; ++k) {
        double n = 2.0 * k + 1, q = n * LV_PI;
        s += 4.0 / q * sin(q * a) * (exp(-q * (2 + b)) - exp(-q * (2 - b))) / (-expm1(-2 * q));
    }
    return s;
}

double lv_exact96(double x, double y, const double psi[4], int nterms)
{
    return psi[0] * side96(x, y, nterms) + psi[2] * side96(x, 1 - y, nterms) +
           psi[3] * side96(y, x, nterms) + psi[1] * side96(y, 1 - x, nterms);
}

double lv_exact98(double x, double y, const double psi[4])
{
    /* (98) with L = H = 1: u = psi1 + psi3 y + sum [2 psi2 cosh(l x) + 2 psi4 cosh(l (1-x))]
     * / (l^2 sinh l) sin(l y), l = (2n-1) pi / 2; cosh/sinh as exponentials (no overflow). The
     * terms decay like e^{-l dmin} / l^2 with dmin the distance to the nearer x face. */
    double dmin = fmin(x, 1 - x);
    long nmax = dmin > 0 ? (long)ceil(40.0 / (LV_PI * dmin)) + 2 : 20000;
    if (nmax > 2000000)
        nmax = 2000000;
    double s = psi[0] + psi[2] * y, tol = 1e-17 * (fabs(psi[1]) + fabs(psi[3]) + 1);
    for (long k = 1; k <= nmax; ++k) {
        double l = (2.0 * k - 1) * LV_PI / 2, den = -expm1(-2 * l);
        /* cosh(l x)/sinh(l) = e^{l (x-1)} (1 + e^{-2 l x}) / (1 - e^{-2 l}) */
        double c2 = exp(l * (x - 1)) * (1 + exp(-2 * l * x)) / den;
        double c4 = exp(-l * x) * (1 + exp(-2 * l * (1 - x))) / den;
        double t = (2 * psi[1] * c2 + 2 * psi[3] * c4) / (l * l);
        s += t * sin(l * y);
        if (dmin > 0 && fabs(t) < tol)
            break;
    }
    return s;
}

void lv_case_free(lv_case *pc)
{
    if (!pc)
        return;
    pst_nlist_destroy(pc->nlist);
    pst_cloud_destroy(pc->cloud);
    free(pc->b);
    free(pc->exact);
    memset(pc, 0, sizeof *pc);
}

int lv_case_build(lv_case *pc, lv_problem prob, int n, double f, double jitter, uint64_t seed,
                  char *err)
{
    memset(pc, 0, sizeof *pc);
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = 2;
    o.lo[0] = o.lo[1] = 0;
    o.hi[0] = o.hi[1] = 1;
    o.s0 = 1.0 / n;
    o.h_ratio = f;
    o.jitter = jitter;
    o.seed = seed;
    int st = pst_cloud_cell_centred(&pc->cloud, &o, err);
    if (st != PST_OK)
        return st;
    pst_cloud *c = pc->cloud;
    size_t np = pst_cloud_size(c);
    pc->n = np;
    pc->b = calloc(np, sizeof *pc->b);
    pc->exact = calloc(np, sizeof *pc->exact);
    if (!pc->b || !pc->exact) {
        lv_case_free(pc);
        snprintf(err, PST_ERRLEN, "lv_case_build: out of memory");
        return PST_ENOMEM;
    }
    const double *x = pst_cloud_coord_const(c, 0), *y = pst_cloud_coord_const(c, 1);
    const double *nx = pst_cloud_normal(c, 0), *ny = pst_cloud_normal(c, 1);
    uint8_t *kind = pst_cloud_kinds(c);
    for (size_t p = 0; p < np; ++p) {
        int side = kind[p] == PST_INTERIOR ? -1 : face_side(nx[p], ny[p]);
        if (side < 0) {
            ++pc->ninterior;
            pc->exact[p] = prob == LV_DIRICHLET_ALL ? lv_exact96(x[p], y[p], lv_psi, 0)
                                                    : lv_exact98(x[p], y[p], lv_psi);
            continue;
        }
        if (prob == LV_DIRICHLET_ALL || side == 0) {
            kind[p] = PST_DIRICHLET;
            pc->b[p] = pc->exact[p] = lv_psi[side];
        } else {
            /* psi2, psi3, psi4 are the outward normal derivatives (M = I): g_N = psi */
            kind[p] = PST_NEUMANN;
            pc->b[p] = lv_psi[side];
            pc->exact[p] = lv_exact98(x[p], y[p], lv_psi);
        }
    }
    st = pst_nlist_build(&pc->nlist, c, pst_kernel_support(PST_KERNEL_CUBIC), err);
    if (st != PST_OK)
        lv_case_free(pc);
    return st;
}

double lv_error95(const pst_cloud *c, const double *exact, const double *uh)
{
    const uint8_t *kind = pst_cloud_kinds_const(c);
    const double *V = pst_cloud_volume_const(c);
    double num = 0, vol = 0;
    for (size_t p = 0; p < pst_cloud_size(c); ++p) {
        if (kind[p] != PST_INTERIOR)
            continue;
        double r = (exact[p] - uh[p]) / exact[p];
        num += V[p] * r * r;
        vol += V[p];
    }
    return vol > 0 ? sqrt(num / vol) : 0;
}

int lv_solve_scheme(const lv_case *pc, const char *scheme, double *uh, int *iters, char *err)
{
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = scheme;
    oo.kernel = PST_KERNEL_CUBIC;
    pst_op *op = NULL;
    int st = pst_op_create(&op, pc->cloud, pc->nlist, &oo, err);
    if (st != PST_OK)
        return st;
    /* the stored weights: the matrix-free apply's bits (docs/operators.md), at a quarter of its
     * time in solves of hundreds to thousands of iterations */
    st = pst_op_store(op);
    if (st != PST_OK) {
        snprintf(err, PST_ERRLEN, "lv_solve_scheme: cannot store the weights (%s)",
                 pst_strerror(st));
        pst_op_destroy(op);
        return st;
    }
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.stored = 1;
    /* cb: AUTO is CG on the symmetrised system when there are no Neumann rows (Jacobi-GMRES
     * stalls near 1e-9 there); every other case GMRES(50) + Jacobi */
    so.solver = strcmp(scheme, "cb") == 0 ? PST_SOLVER_AUTO : PST_SOLVER_GMRES;
    so.precond = PST_PREC_JACOBI;
    so.rtol = 1e-10;
    so.max_iter = 20000;
    pst_solve_result r;
    memset(&r, 0, sizeof r);
    memset(uh, 0, pc->n * sizeof *uh);
    st = pst_solve(op, pc->b, uh, &so, &r, err);
    if (iters)
        *iters = r.iterations;
    pst_solve_result_free(&r);
    /* cb with Neumann rows at f = 0.5005 is too ill-conditioned for GMRES (LV §5.2: "badly
     * conditioned"); small systems fall back to a dense LU, iters = -1 says so */
    if (st == PST_ENUMERIC && pc->n <= 4000) {
        st = lv_solve_dense(op, pc->b, uh, err);
        if (iters)
            *iters = -1;
    }
    pst_op_destroy(op);
    return st;
}

int lv_solve_dense(const pst_op *op, const double *b, double *uh, char *err)
{
    pst_csr a;
    memset(&a, 0, sizeof a);
    int st = pst_op_assemble(op, &a);
    if (st != PST_OK) {
        snprintf(err, PST_ERRLEN, "lv_solve_dense: assembly failed (%s)", pst_strerror(st));
        return st;
    }
    st = lv_solve_dense_csr(&a, b, uh, err);
    pst_csr_free(&a);
    return st;
}

int lv_solve_dense_csr(const pst_csr *a, const double *b, double *uh, char *err)
{
    size_t n = a->n;
    if (n > 4000) {
        snprintf(err, PST_ERRLEN, "lv_solve_dense: %zu unknowns is too many for a dense LU", n);
        return PST_EINVAL;
    }
    double *m = calloc(n * n, sizeof *m);
    lapack_int *piv = malloc(n * sizeof *piv);
    if (!m || !piv) {
        free(m);
        free(piv);
        snprintf(err, PST_ERRLEN, "lv_solve_dense: out of memory");
        return PST_ENOMEM;
    }
    for (size_t i = 0; i < n; ++i)
        for (int64_t k = a->rowptr[i]; k < a->rowptr[i + 1]; ++k)
            m[i + n * a->col[k]] = a->val[k]; /* column major */
    memcpy(uh, b, n * sizeof *uh);
    lapack_int info = LAPACKE_dgesv(LAPACK_COL_MAJOR, (lapack_int)n, 1, m, (lapack_int)n, piv,
                                    uh, (lapack_int)n);
    free(m);
    free(piv);
    if (info != 0) {
        snprintf(err, PST_ERRLEN, "lv_solve_dense: dgesv info %d", (int)info);
        return PST_ENUMERIC;
    }
    return PST_OK;
}

double lv_fit_rate(const int *sides, const double *err, int m)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < m; ++k) {
        double X = log2((double)sides[k]), Y = log2(err[k]);
        sx += X;
        sy += Y;
        sxx += X * X;
        sxy += X * Y;
    }
    return -(m * sxy - sx * sy) / (m * sxx - sx * sx);
}

int lv_tpfa_error(lv_problem prob, int n, double *e95, char *err)
{
    size_t nc = (size_t)n * (size_t)n;
    double *k = malloc(nc * sizeof *k), *u = malloc(nc * sizeof *u);
    if (!k || !u) {
        free(k);
        free(u);
        snprintf(err, PST_ERRLEN, "lv_tpfa_error: out of memory");
        return -1;
    }
    for (size_t c = 0; c < nc; ++c)
        k[c] = 1;
    tpfa_problem p = {.dim = 2, .n = {n, n, 1}, .d = {1.0 / n, 1.0 / n, 1}, .k = {k, k, NULL}};
    /* tpfa sides x lo, x hi, y lo, y hi are the paper's psi4, psi2, psi1, psi3 */
    const int paper[4] = {3, 1, 0, 2};
    for (int s = 0; s < 4; ++s) {
        p.bc_kind[s] = (prob == LV_DIRICHLET_ALL || s == 2) ? TPFA_DIRICHLET : TPFA_FLUX;
        p.bc_value[s] = lv_psi[paper[s]];
    }
    int st = tpfa_solve(&p, u, err, PST_ERRLEN);
    if (st == 0) {
        double num = 0;
        for (size_t c = 0; c < nc; ++c) {
            double x = ((double)(c % (size_t)n) + 0.5) / n, y = ((double)(c / (size_t)n) + 0.5) / n;
            double e = prob == LV_DIRICHLET_ALL ? lv_exact96(x, y, lv_psi, 0) : lv_exact98(x, y, lv_psi);
            num += ((e - u[c]) / e) * ((e - u[c]) / e);
        }
        *e95 = sqrt(num / (double)nc);
    }
    free(k);
    free(u);
    return st;
}

int lv_spe10_case(const pst_perm_grid *g, double f, pst_cloud **cout, pst_nlist **nlout,
                  double **bout, char *err)
{
    *cout = NULL;
    *nlout = NULL;
    *bout = NULL;
    int dim = g->nz > 1 ? 3 : 2;
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = dim;
    o.s0 = 1.0 / g->nx;
    const int nc[3] = {g->nx, g->ny, g->nz};
    for (int d = 0; d < 3; ++d) {
        o.lo[d] = 0;
        o.hi[d] = nc[d] * o.s0;
    }
    o.h_ratio = f;
    pst_cloud *c = NULL;
    int st = pst_cloud_cell_centred(&c, &o, err);
    if (st != PST_OK)
        return st;
    /* one grid cell per cloud cell: scale_a = s0 / d_a */
    const double scale[3] = {o.s0 / g->dx, o.s0 / g->dy, o.s0 / g->dz};
    st = pst_cloud_mobility_from_grid(c, g, NULL, scale, 1, err);
    size_t np = pst_cloud_size(c);
    double *b = st == PST_OK ? calloc(np, sizeof *b) : NULL;
    if (st == PST_OK && !b) {
        snprintf(err, PST_ERRLEN, "lv_spe10_case: out of memory");
        st = PST_ENOMEM;
    }
    if (st != PST_OK) {
        pst_cloud_destroy(c);
        return st;
    }
    const double *ny = pst_cloud_normal(c, 1);
    uint8_t *kind = pst_cloud_kinds(c);
    for (size_t p = 0; p < np; ++p) {
        if (kind[p] == PST_INTERIOR)
            continue;
        if (ny[p] < -0.5) {
            kind[p] = PST_DIRICHLET; /* y = 0: u = 1 */
            b[p] = 1.0;
        } else if (ny[p] > 0.5) {
            kind[p] = PST_DIRICHLET; /* y = ymax: u = 0 */
            b[p] = 0.0;
        } else {
            kind[p] = PST_NEUMANN; /* no flow */
            b[p] = 0.0;
        }
    }
    pst_nlist *nl = NULL;
    st = pst_nlist_build(&nl, c, pst_kernel_support(PST_KERNEL_CUBIC), err);
    if (st != PST_OK) {
        free(b);
        pst_cloud_destroy(c);
        return st;
    }
    *cout = c;
    *nlout = nl;
    *bout = b;
    return PST_OK;
}

int lv_spe10_stack_84_85(pst_perm_grid *g, const char *permx_path, int ni, int nj, char *err)
{
    memset(g, 0, sizeof *g);
    pst_perm_grid l84, l85;
    int st = pst_spe10_read(&l84, permx_path, 84, 0, 0, ni, nj, err);
    if (st != PST_OK)
        return st;
    st = pst_spe10_read(&l85, permx_path, 85, 0, 0, ni, nj, err);
    if (st != PST_OK) {
        pst_perm_grid_free(&l84);
        return st;
    }
    size_t layer = (size_t)ni * (size_t)nj;
    *g = (pst_perm_grid){.nx = ni, .ny = nj, .nz = 2, .dx = l84.dx, .dy = l84.dy, .dz = l84.dz};
    for (int k = 0; k < 3; ++k) {
        g->k[k] = malloc(2 * layer * sizeof *g->k[k]);
        if (!g->k[k]) {
            st = PST_ENOMEM;
            continue;
        }
        memcpy(g->k[k], l84.k[k], layer * sizeof *g->k[k]);          /* l = 0: layer 84 */
        memcpy(g->k[k] + layer, l85.k[k], layer * sizeof *g->k[k]);  /* l = 1: layer 85 */
    }
    pst_perm_grid_free(&l84);
    pst_perm_grid_free(&l85);
    if (st != PST_OK) {
        for (int k = 0; k < 3; ++k)
            free(g->k[k]);
        memset(g, 0, sizeof *g);
        snprintf(err, PST_ERRLEN, "lv_spe10_stack_84_85: out of memory");
    }
    return st;
}
