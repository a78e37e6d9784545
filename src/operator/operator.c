/* The operator object: creation, the stored-weight path, diagonal, assembly,
 * status counts and the monotonicity audit. Everything here is derived from a scheme's
 * emit_row, so a new scheme gets all of it by filling its table (operator.h). */
#include "operator.h"
#include "check.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

const char *pst_phase_name(int phase)
{
    static const char *const names[PST_NPHASES] = {"geometry", "moments",    "inversion",
                                                   "weights",  "precompute", "apply"};
    return phase >= 0 && phase < PST_NPHASES ? names[phase] : "unknown";
}

void pst_op_phase_times(const pst_op *op, double t[PST_NPHASES])
{
    memcpy(t, op->phase, sizeof op->phase);
}

const char *pst_row_status_name(int status)
{
    static const char *const names[PST_ROW_NSTATUS] = {"ok", "fallback", "ill-conditioned",
                                                       "rank-deficient", "too-few-neighbours"};
    return status >= 0 && status < PST_ROW_NSTATUS ? names[status] : "unknown";
}

void pst_op_defaults(pst_op_opts *o)
{
    o->scheme = "qsfdi"; /* the scenes' default too: one default scheme everywhere */
    o->kernel = -1;
    o->gradient = PST_GRAD_G1;
    o->variant = 0;
    o->cond_max = 1e10;
    o->rank_tol = 1e-13;
    o->min_pair_distance = 1e-8;
    o->on_degenerate = PST_DEGENERATE_FALL_BACK;
    o->laplacian = 1;
    o->keep = 0;
    o->mobility_mean = PST_MEAN_ARITHMETIC;
    o->kinds = NULL;
    o->normals[0] = o->normals[1] = o->normals[2] = NULL;
    o->progress.fn = NULL;
    o->progress.user = NULL;
}

/* The boundary override of opts (kinds, normals): known kinds, finite Neumann normals. */
static int check_boundary(const pst_op_opts *o, const pst_cloud *c, char *err)
{
    const uint8_t *kind = o->kinds ? o->kinds : c->kind;
    for (int a = 0; a < c->dim && o->normals[0]; ++a)
        PST_CHECK(!o->normals[a], PST_EINVAL, err, "boundary normals: component %d is NULL", a);
    for (size_t i = 0; i < c->n; ++i) {
        PST_CHECK(kind[i] > PST_NEUMANN, PST_EINVAL, err,
                  "boundary kinds: particle %zu has unknown kind %d", i, kind[i]);
        double len = 0;
        for (int a = 0; a < c->dim && o->normals[0] && kind[i] == PST_NEUMANN; ++a) {
            PST_CHECK(!isfinite(o->normals[a][i]), PST_EINVAL, err,
                      "boundary normals: Neumann particle %zu has a non-finite normal", i);
            len += o->normals[a][i] * o->normals[a][i];
        }
        PST_CHECK(o->normals[0] && kind[i] == PST_NEUMANN && !(len > 0), PST_EINVAL, err,
                  "boundary normals: Neumann particle %zu has a zero normal", i);
    }
    return PST_OK;
}

static int check_opts(const pst_op_opts *o, const pst_cloud *c, const pst_nlist *nl,
                      const pst_scheme **scheme, char *err)
{
    char names[256];
    *scheme = pst_scheme_find(o->scheme);
    PST_CHECK(!*scheme, PST_EINVAL, err, "unknown scheme '%s' (known: %s)",
              o->scheme ? o->scheme : "(null)", pst_scheme_names(names, sizeof names));
    PST_CHECK(o->kernel < -1 || o->kernel > PST_KERNEL_WENDLAND_C4, PST_EINVAL, err,
              "unknown kernel %d", o->kernel);
    PST_CHECK(o->gradient < PST_GRAD_G1 || o->gradient > PST_GRAD_G4, PST_EINVAL, err,
              "gradient variant must be G1..G4 (got %d)", o->gradient);
    PST_CHECK(!(o->cond_max >= 1) || !(o->rank_tol > 0 && o->rank_tol < 1), PST_EINVAL, err,
              "cond_max must be >= 1 and rank_tol in (0, 1) (got %g, %g)", o->cond_max,
              o->rank_tol);
    PST_CHECK(!(o->min_pair_distance > 0 && o->min_pair_distance < 0.5), PST_EINVAL, err,
              "min_pair_distance must be in (0, 0.5) (got %g)", o->min_pair_distance);
    PST_CHECK(o->on_degenerate != PST_DEGENERATE_FALL_BACK &&
                  o->on_degenerate != PST_DEGENERATE_REFUSE,
              PST_EINVAL, err,
              "on_degenerate must be PST_DEGENERATE_FALL_BACK (0) or PST_DEGENERATE_REFUSE (1) "
              "(got %d)",
              o->on_degenerate);
    PST_CHECK(o->mobility_mean != PST_MEAN_ARITHMETIC && o->mobility_mean != PST_MEAN_HARMONIC,
              PST_EINVAL, err,
              "mobility_mean must be PST_MEAN_ARITHMETIC (0) or PST_MEAN_HARMONIC (1) (got %d)",
              o->mobility_mean);
    PST_CHECK(o->mobility_mean == PST_MEAN_HARMONIC && !(*scheme)->pair_mobility, PST_EINVAL,
              err,
              "scheme '%s' does not average the mobility pairwise: the harmonic mobility mean "
              "applies only to brookshaw, cb, schwaiger and lv",
              (*scheme)->name);
    PST_CHECK((*scheme)->variants <= 1 && o->variant != 0, PST_EINVAL, err,
              "%s has no variants (got variant %d)", (*scheme)->name, o->variant);
    /* a scheme without a heterogeneous form cannot build rows on a mobility (its derivatives
     * alone, opts.laplacian = 0, do not read it) */
    PST_CHECK(!(*scheme)->mobility && c->mob_ncomp != 0 &&
                  (o->laplacian || !(*scheme)->derivatives_standalone),
              PST_EINVAL, err,
              "%s discretises the plain Laplacian only: it has no heterogeneous form, so the "
              "cloud must have no mobility (it has %d components)",
              (*scheme)->name, c->mob_ncomp);
    PST_CHECK(o->keep & ~(PST_KEEP_GRADIENT | PST_KEEP_HESSIAN), PST_EINVAL, err,
              "keep must be a combination of PST_KEEP_GRADIENT (1) and PST_KEEP_HESSIAN (2) "
              "(got %d)",
              o->keep);
    PST_CHECK(o->keep && !(*scheme)->keep_bytes[1][0], PST_EINVAL, err,
              "%s keeps no derivative weights (keep = %d): only qsfdi, lsmps, lpmps and the "
              "CSPM family (cspm, icspm, csph2g) do; its derivatives are computed when asked",
              (*scheme)->name, o->keep);
    PST_CHECK((o->keep & PST_KEEP_HESSIAN) && !(*scheme)->hessian, PST_EINVAL, err,
              "%s has no Hessian estimate, so it cannot keep one (keep = %d)", (*scheme)->name,
              o->keep);
    PST_CHECK(o->keep && !o->laplacian, PST_EINVAL, err,
              "keep needs the rows (laplacian = 1): without them the derivatives are computed "
              "in one pass when asked, which is what keeping would save");
    PST_CHECK(pst_nlist_is_half(nl), PST_EINVAL, err,
              "an operator needs the whole neighbour list: a half list (pst_nlist_halve) serves "
              "an operator already built, through pst_op_use_half_list");
    PST_CHECK(pst_nlist_rows(nl) != c->n, PST_EINVAL, err,
              "the neighbour list has %zu rows for a cloud of %zu particles", pst_nlist_rows(nl),
              c->n);
    PST_TRY(check_boundary(o, c, err));
    pst_kernel k = o->kernel < 0 ? (*scheme)->default_kernel : (pst_kernel)o->kernel;
    PST_CHECK(pst_nlist_support(nl) < pst_kernel_support(k), PST_EINVAL, err,
              "the neighbour list's radius (%g h) is smaller than the support of the %s kernel "
              "(%g h): rebuild it with support %g",
              pst_nlist_support(nl), pst_kernel_name(k), pst_kernel_support(k),
              pst_kernel_support(k));
    return PST_OK;
}

/* op->xyzu: the positions, packed before the precompute and the flat-row check, which read
 * them; u = 0 until an apply or a derivative writes it. Kept by a lane scheme, whose applies
 * (and qsfdi's derivatives) read it. */
static int pack_positions(pst_op *op)
{
    const pst_cloud *c = op->cloud;
    if (!op->xyzu) /* a refresh packs into the array the operator kept */
        op->xyzu = pst_alloc(op->n * 4 * sizeof *op->xyzu);
    double *p = op->xyzu;
    if (!p)
        return PST_ENOMEM;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i) {
        p[4 * i] = c->x[0][i];
        p[4 * i + 1] = c->x[1][i];
        p[4 * i + 2] = c->dim == 3 ? c->x[2][i] : 0.0;
        p[4 * i + 3] = 0.0;
    }
    return PST_OK;
}

/* PST_DEGENERATE_REFUSE: an operator with a rank-deficient or too-few-neighbours row is an
 * error that names the counts and the first such particle (input order). */
static int refuse_degenerate(const pst_op *op, char *err)
{
    size_t rank = op->counts[PST_ROW_RANK_DEFICIENT], few = op->counts[PST_ROW_TOO_FEW];
    if (rank + few == 0)
        return PST_OK;
    const pst_cloud *c = op->cloud;
    size_t first = 0;
    int64_t first_id = INT64_MAX;
    for (size_t i = 0; i < c->n; ++i)
        if (op->status[i] >= PST_ROW_RANK_DEFICIENT && c->id[i] < first_id) {
            first_id = c->id[i];
            first = i;
        }
    pst_set_err(err, "%s: %zu degenerate rows (%zu rank-deficient, %zu too-few-neighbours); "
                     "the first is particle %lld at (%g, %g, %g), %s; on_degenerate = refuse",
                op->scheme->name, rank + few, rank, few, (long long)first_id, c->x[0][first],
                c->x[1][first], c->dim == 3 ? c->x[2][first] : 0.0,
                pst_row_status_name(op->status[first]));
    return PST_ENUMERIC;
}

/* The precompute of a created or refreshed operator: the packed positions, the scheme's
 * rows, the flat-row check, the rows' status and counts (op->status zeroed on entry), the
 * refusal of degenerate rows when asked. */
static int precompute(pst_op *op, char *err)
{
    const pst_op_opts *o = &op->opts;
    const pst_scheme *scheme = op->scheme;
    const pst_cloud *c = op->cloud;
    const pst_nlist *nl = op->nl;
    /* Derivatives only: the rows are skipped when the scheme's derivative estimates do not
     * read them (the planner's "model only what a scene needs"). */
    op->rows = o->laplacian || !scheme->derivatives_standalone;
    if ((scheme->lanes || (op->rows && scheme->degrade)) && pack_positions(op) != PST_OK) {
        pst_set_err(err, "cannot allocate the packed positions of %zu particles", c->n);
        return PST_ENOMEM;
    }
    if (!scheme->wide_pattern) { /* a wide pattern is built only where it is read */
        op->poff = pst_nlist_offsets(nl);
        op->pidx = pst_nlist_indices(nl);
    }
    double t0 = omp_get_wtime();
    pst_tally tally;
    op->tally = op->rows ? pst_tally_start(&tally, &o->progress, c->n) : NULL;
    int st = op->rows ? scheme->precompute(op, err) : PST_OK;
    if (st == PST_OK && op->rows)
        pst_op_check_flat_rows(op);
    if (!scheme->lanes) { /* only the flat-row check read it */
        pst_free(op->xyzu);
        op->xyzu = NULL;
    }
    if (st == PST_OK)
        pst_tally_finish(op->tally);
    op->tally = NULL;
    op->phase[PST_PHASE_PRECOMPUTE] = omp_get_wtime() - t0;
    if (st != PST_OK)
        return st;
    for (size_t i = 0; i < c->n; ++i)
        if (op->kind[i] == PST_DIRICHLET)
            op->status[i] = PST_ROW_OK; /* identity rows need nothing */
    for (size_t i = 0; i < c->n; ++i)
        op->counts[op->status[i]]++;
    if (o->on_degenerate == PST_DEGENERATE_REFUSE)
        return refuse_degenerate(op, err);
    return PST_OK;
}

int pst_op_create(pst_op **out, const pst_cloud *c, const pst_nlist *nl, const pst_op_opts *o,
                  char *err)
{
    *out = NULL;
    pst_op_opts defaults;
    if (!o) {
        pst_op_defaults(&defaults);
        o = &defaults;
    }
    const pst_scheme *scheme;
    PST_TRY(check_opts(o, c, nl, &scheme, err));
    pst_op *op = calloc(1, sizeof *op);
    PST_CHECK_ALLOC(op, err, "cannot allocate an operator");
    op->scheme = scheme;
    op->cloud = c;
    op->nl = nl;
    op->opts = *o;
    op->opts.scheme = scheme->name; /* static storage: the caller's string may go away */
    op->kernel = o->kernel < 0 ? scheme->default_kernel : (pst_kernel)o->kernel;
    op->dim = c->dim;
    op->n = c->n;
    op->kind = o->kinds ? o->kinds : c->kind;
    for (int a = 0; a < c->dim; ++a)
        op->normal[a] = o->normals[0] ? o->normals[a] : c->normal[a];
    op->status = pst_calloc(c->n, 1);
    if (!op->status) {
        pst_op_destroy(op);
        pst_set_err(err, "cannot allocate the row status of %zu particles", c->n);
        return PST_ENOMEM;
    }
    int st = precompute(op, err);
    if (st != PST_OK) {
        pst_op_destroy(op);
        return st;
    }
    *out = op;
    return PST_OK;
}

/* What a store made, released for a refresh: the stored weights and a wide pattern (the
 * scheme's data stays for the precompute to fill again, pst_op_data; so do the operator's
 * status, packed positions and handle). */
static void release_rows(pst_op *op)
{
    pst_op_park_store(op);
    op->poff = NULL; /* the list's arrays may have moved (pst_nlist_update) */
    op->pidx = NULL;
    memset(op->status, 0, op->n);
    memset(op->counts, 0, sizeof op->counts);
}

int pst_op_refresh(pst_op *op, char *err)
{
    PST_CHECK(!op, PST_EINVAL, err, "pst_op_refresh needs an operator");
    PST_CHECK(op->half, PST_EINVAL, err,
              "operator refresh: the operator runs on a half list (pst_op_use_half_list); "
              "create it again on the updated whole list");
    PST_CHECK(op->cloud->n != op->n || pst_nlist_rows(op->nl) != op->n, PST_EINVAL, err,
              "operator refresh: the operator has %zu rows, the cloud %zu particles and the "
              "list %zu rows",
              op->n, op->cloud->n, pst_nlist_rows(op->nl));
    const pst_scheme *scheme;
    PST_TRY(check_opts(&op->opts, op->cloud, op->nl, &scheme, err));
    pst_op_store_opts store;
    pst_op_store_defaults(&store);
    store.precision = pst_op_store_precision(op);
    release_rows(op);
    int st = precompute(op, err);
    if (st == PST_OK && store.precision != PST_STORE_NONE)
        st = pst_op_store_with(op, &store, err);
    if (st != PST_OK) { /* an operator without rows: every apply refuses it */
        release_rows(op);
        op->rows = 0;
    }
    return st;
}

void pst_op_destroy(pst_op *op)
{
    if (!op)
        return;
    if (op->data && op->scheme->free_data)
        op->scheme->free_data(op->data);
    pst_free(op->status);
    pst_op_drop_store(op);
    pst_free(op->own_poff);
    pst_free(op->own_pidx);
    pst_half_schedule_free(op->half);
    pst_free(op->half_diag);
    pst_free(op->xyzu);
    free(op);
}

const uint8_t *pst_op_status(const pst_op *op) { return op->status; }
void pst_op_status_counts(const pst_op *op, size_t counts[PST_ROW_NSTATUS])
{
    memcpy(counts, op->counts, sizeof op->counts);
}

/* The element-wise passes of an apply or a derivative (u into the packed rows, the Dirichlet
 * rows: about a nanosecond per particle) take the threads only above this many particles:
 * below it a parallel region's fork and join cost more than the loop (tens of microseconds
 * where the idle threads sleep, as under OMP_WAIT_POLICY=PASSIVE). Element-wise: the same
 * bits. */
#define APPLY_PASS_THREADED(n) ((n) > 16384)

/* Dirichlet rows are the identity: their values are data. */
static void dirichlet_rows(const pst_op *op, const double *u, double *y)
{
    const uint8_t *kind = op->kind;
#pragma omp parallel for schedule(static) if (APPLY_PASS_THREADED(op->n))
    for (size_t i = 0; i < op->n; ++i)
        if (kind[i] == PST_DIRICHLET)
            y[i] = u[i];
}

/* The apply timer is the one field an apply writes; applies of one operator are not meant to
 * run concurrently (they are parallel inside). */
void pst_op_record_apply(const pst_op *op, double t0)
{
    ((pst_op *)op)->phase[PST_PHASE_APPLY] = omp_get_wtime() - t0;
}

/* u into op->xyzu for the lane rows of an apply or a derivative: a strided write of 8 bytes per
 * particle, about 1 % of an apply's time. */
static void pack_values(const pst_op *op, const double *u)
{
    double *p = op->xyzu;
#pragma omp parallel for schedule(static) if (APPLY_PASS_THREADED(op->n))
    for (size_t i = 0; i < op->n; ++i)
        p[4 * i + 3] = u[i];
}

int pst_op_apply(const pst_op *op, const double *u, double *y)
{
    if (!op->rows)
        return PST_EINVAL;
    double t0 = omp_get_wtime();
    if (op->xyzu) /* the lane rows, of the whole list or of a half list, read u there */
        pack_values(op, u);
    if (op->half)
        pst_op_apply_half(op, u, y);
    else
        op->scheme->apply(op, u, y);
    dirichlet_rows(op, u, y);
    pst_op_record_apply(op, t0);
    return PST_OK;
}

int pst_op_has_rows(const pst_op *op) { return op->rows; }
const char *pst_op_scheme(const pst_op *op) { return op->scheme->name; }
pst_kernel pst_op_kernel(const pst_op *op) { return op->kernel; }
void pst_op_options(const pst_op *op, pst_op_opts *o)
{
    *o = op->opts;
    o->scheme = op->scheme->name;
    o->kernel = op->kernel;
}

/* A wide pattern not built yet is counted (offsets only, no index). */
int64_t pst_op_pattern_pairs(const pst_op *op)
{
    if (op->half)
        return 2 * pst_nlist_pairs(op->nl);
    if (op->poff)
        return op->poff[op->n];
    int64_t *off;
    if (op->scheme->wide_pattern(op, &off, NULL, NULL) != PST_OK)
        return -1;
    int64_t pairs = off[op->n];
    pst_free(off);
    return pairs;
}

/* A read-only path's operator with the rows' pattern in place: op itself when it has one,
 * else a copy of op pointing at a wide pattern built for this call (pattern_view_free frees
 * it). Building it into op instead would write through a const operator that concurrent
 * read-only calls may share; the copy writes nothing shared, and the pattern (4 bytes per
 * entry, ~6 GB for a 3D mixed scheme at 10^6) does not outlive the call. NULL: no memory. */
typedef struct {
    pst_op copy;
    int64_t *poff;
    uint32_t *pidx;
} pattern_view;

static const pst_op *pattern_view_of(const pst_op *op, pattern_view *v)
{
    v->poff = NULL;
    v->pidx = NULL;
    if (op->poff)
        return op;
    if (op->scheme->wide_pattern(op, &v->poff, &v->pidx, NULL) != PST_OK)
        return NULL;
    v->copy = *op;
    v->copy.poff = v->poff;
    v->copy.pidx = v->pidx;
    return &v->copy;
}

static void pattern_view_free(pattern_view *v)
{
    pst_free(v->poff);
    pst_free(v->pidx);
}

/* The weights of row i, from the store or emitted into `buf`. */
static const double *row_weights(const pst_op *op, size_t i, double *buf)
{
    const int64_t *off = op->poff;
    if (op->w)
        return op->w + off[i];
    op->scheme->emit_row(op, i, buf);
    return buf;
}

/* Scratch for one row of weights per thread (rows are at most the pattern's longest row). */
static double *row_scratch(const pst_op *op, size_t *len)
{
    int64_t longest = 0;
    for (size_t i = 0; i < op->n; ++i)
        longest = op->poff[i + 1] - op->poff[i] > longest ? op->poff[i + 1] - op->poff[i] : longest;
    *len = (size_t)longest + 1;
    return op->w ? NULL : pst_alloc((size_t)omp_get_max_threads() * *len * sizeof(double));
}

static int diagonal_rows(const pst_op *op, double *diag)
{
    const int64_t *off = op->poff;
    const uint8_t *kind = op->kind;
    size_t L;
    double *scratch = row_scratch(op, &L);
    if (!op->w && !scratch)
        return PST_ENOMEM;
#pragma omp parallel
    {
        double *buf = scratch ? scratch + (size_t)omp_get_thread_num() * L : NULL;
#pragma omp for schedule(dynamic, 256)
        for (size_t i = 0; i < op->n; ++i) {
            if (kind[i] == PST_DIRICHLET) {
                diag[i] = 1.0;
                continue;
            }
            const double *w = row_weights(op, i, buf);
            double s = 0;
            for (int64_t k = 0; k < off[i + 1] - off[i]; ++k)
                s += w[k];
            diag[i] = -s;
        }
    }
    pst_free(scratch);
    return PST_OK;
}

int pst_op_diagonal(const pst_op *op, double *diag)
{
    if (!op->rows)
        return PST_EINVAL;
    if (op->half_diag) {
        memcpy(diag, op->half_diag, op->n * sizeof *diag);
        return PST_OK;
    }
    pattern_view v;
    const pst_op *p = pattern_view_of(op, &v);
    int st = p ? diagonal_rows(p, diag) : PST_ENOMEM;
    pattern_view_free(&v);
    return st;
}

int pst_op_scale(const pst_op *op, double *s)
{
    if (!op->rows)
        return PST_EINVAL;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < op->n; ++i)
        s[i] = op->scheme->scale ? op->scheme->scale(op, i) : 1.0;
    return PST_OK;
}

void pst_csr_free(pst_csr *a)
{
    if (!a)
        return;
    pst_free(a->rowptr);
    pst_free(a->col);
    pst_free(a->val);
    memset(a, 0, sizeof *a);
}

/* Row i of the explicit matrix: the off-diagonal weights and the diagonal merged in column
 * order (list rows are sorted; the diagonal is inserted where it belongs). */
static int assemble_rows(const pst_op *op, pst_csr *a)
{
    size_t n = op->n;
    const int64_t *off = op->poff;
    const uint32_t *idx = op->pidx;
    const uint8_t *kind = op->kind;
    a->n = n;
    a->rowptr = pst_alloc((n + 1) * sizeof *a->rowptr);
    a->col = pst_alloc(((size_t)off[n] + n) * sizeof *a->col);
    a->val = pst_alloc(((size_t)off[n] + n) * sizeof *a->val);
    size_t L;
    double *scratch = row_scratch(op, &L);
    if (!a->rowptr || !a->col || !a->val || (!op->w && !scratch)) {
        pst_csr_free(a);
        pst_free(scratch);
        return PST_ENOMEM;
    }
    for (size_t i = 0; i <= n; ++i)
        a->rowptr[i] = off[i] + (int64_t)i;
#pragma omp parallel
    {
        double *buf = scratch ? scratch + (size_t)omp_get_thread_num() * L : NULL;
#pragma omp for schedule(dynamic, 256)
        for (size_t i = 0; i < n; ++i) {
            int64_t len = off[i + 1] - off[i], o = a->rowptr[i];
            int dirichlet = kind[i] == PST_DIRICHLET;
            const double *w = dirichlet ? NULL : row_weights(op, i, buf);
            double diag = 0;
            for (int64_t k = 0; k < len; ++k)
                diag -= dirichlet ? 0 : w[k];
            int64_t k = 0, p = o;
            for (; k < len && idx[off[i] + k] < i; ++k, ++p) {
                a->col[p] = idx[off[i] + k];
                a->val[p] = dirichlet ? 0 : w[k];
            }
            a->col[p] = (uint32_t)i;
            a->val[p++] = dirichlet ? 1.0 : diag;
            for (; k < len; ++k, ++p) {
                a->col[p] = idx[off[i] + k];
                a->val[p] = dirichlet ? 0 : w[k];
            }
        }
    }
    pst_free(scratch);
    return PST_OK;
}

int pst_op_assemble(const pst_op *op, pst_csr *a)
{
    if (!op->rows || op->half)
        return PST_EINVAL;
    memset(a, 0, sizeof *a);
    pattern_view v;
    const pst_op *p = pattern_view_of(op, &v);
    int st = p ? assemble_rows(p, a) : PST_ENOMEM;
    pattern_view_free(&v);
    return st;
}

typedef struct {
    const pst_csr *a;
    const int64_t *ids;
} mtx_job;

static void write_mtx(FILE *f, const void *job)
{
    const mtx_job *m = job;
    const pst_csr *a = m->a;
    fprintf(f, "%%%%MatrixMarket matrix coordinate real general\n");
    fprintf(f, "%% written by pstencil %s; rows and columns in input order\n", pst_version());
    fprintf(f, "%zu %zu %lld\n", a->n, a->n, (long long)a->rowptr[a->n]);
    for (size_t i = 0; i < a->n && !ferror(f); ++i) {
        long long r = m->ids ? m->ids[i] + 1 : (long long)i + 1;
        for (int64_t k = a->rowptr[i]; k < a->rowptr[i + 1]; ++k) {
            long long c = m->ids ? m->ids[a->col[k]] + 1 : (long long)a->col[k] + 1;
            fprintf(f, "%lld %lld %.17g\n", r, c, a->val[k]);
        }
    }
}

int pst_csr_write_mtx(const pst_csr *a, const int64_t *ids, const char *path, char *err)
{
    mtx_job job = {a, ids};
    return pst_write_atomic(path, write_mtx, &job, err);
}

/* The audit of interior row i from its weights w: the pst_op_audit_flags bits, and the
 * count of positive off-diagonal entries of K in *npos. */
static uint8_t audit_row(const pst_op *op, size_t i, const double *w, int64_t *npos)
{
    const int64_t *off = op->poff;
    double sum = 0, abs_sum = 0;
    *npos = 0;
    for (int64_t k = 0; k < off[i + 1] - off[i]; ++k) {
        *npos += w[k] < 0; /* K = -L: K_IJ = -w_IJ > 0 */
        sum += w[k];
        abs_sum += fabs(w[k]);
    }
    uint8_t f = *npos > 0 ? PST_AUDIT_POSITIVE_OFFDIAG : 0;
    /* K_II = sum w >= sum |w| (to rounding) and > 0 */
    if (!(sum > 0 && sum >= abs_sum * (1 - 1e-12)))
        f |= PST_AUDIT_NOT_DOMINANT;
    if (op->scheme->lemma3) {
        int sm = 0, xl = 0;
        op->scheme->lemma3(op, i, &sm, &xl);
        f |= (sm ? PST_AUDIT_LEMMA3_MIXED : 0) | (xl ? PST_AUDIT_XI_LARGE : 0);
    }
    return f;
}

/* Audit every interior row (threaded): the flags into `flags` (may be NULL) and the totals
 * into a (may be NULL). */
static int audit_rows(const pst_op *op, uint8_t *flags, pst_op_audit *a)
{
    const uint8_t *kind = op->kind;
    size_t L;
    double *scratch = row_scratch(op, &L);
    size_t rows = 0, rows_pos = 0, rows_nd = 0;
    int64_t pos = 0, mixed = 0, large = 0;
    if (!op->w && !scratch)
        return PST_ENOMEM;
#pragma omp parallel reduction(+ : rows, rows_pos, rows_nd, pos, mixed, large)
    {
        double *buf = scratch ? scratch + (size_t)omp_get_thread_num() * L : NULL;
#pragma omp for schedule(dynamic, 256)
        for (size_t i = 0; i < op->n; ++i) {
            uint8_t f = 0;
            if (kind[i] == PST_INTERIOR) { /* boundary rows are data or fluxes */
                int64_t npos;
                f = audit_row(op, i, row_weights(op, i, buf), &npos);
                rows++;
                pos += npos;
                rows_pos += (f & PST_AUDIT_POSITIVE_OFFDIAG) != 0;
                rows_nd += (f & PST_AUDIT_NOT_DOMINANT) != 0;
                mixed += (f & PST_AUDIT_LEMMA3_MIXED) != 0;
                large += (f & PST_AUDIT_XI_LARGE) != 0;
            }
            if (flags)
                flags[i] = f;
        }
    }
    pst_free(scratch);
    if (a) {
        int has_lemma3 = op->scheme->lemma3 != NULL;
        a->rows = rows;
        a->rows_positive_offdiag = rows_pos;
        a->positive_offdiag = pos;
        a->rows_not_dominant = rows_nd;
        a->lemma3_sign_mixed = has_lemma3 ? mixed : -1;
        a->lemma3_xi_large = has_lemma3 ? large : -1;
    }
    return PST_OK;
}

static int audit(const pst_op *op, uint8_t *flags, pst_op_audit *a)
{
    if (!op->rows || op->half)
        return PST_EINVAL;
    pattern_view v;
    const pst_op *p = pattern_view_of(op, &v);
    int st = p ? audit_rows(p, flags, a) : PST_ENOMEM;
    pattern_view_free(&v);
    return st;
}

int pst_op_audit_rows(const pst_op *op, pst_op_audit *a)
{
    memset(a, 0, sizeof *a);
    return audit(op, NULL, a);
}

int pst_op_audit_flags(const pst_op *op, uint8_t *flags) { return audit(op, flags, NULL); }

void pst_op_set_progress(pst_op *op, const pst_progress *progress)
{
    op->opts.progress = progress ? *progress : (pst_progress){NULL, NULL};
}

/* A read-only call's operator with a progress counter of `total` units: op itself without a
 * hook, else a copy that points at the caller's tally (writing the counter into op would
 * write through a const operator that concurrent read-only calls may share). */
static const pst_op *progress_view(const pst_op *op, uint64_t total, pst_op *copy,
                                   pst_tally *tally)
{
    if (!op->opts.progress.fn)
        return op;
    *copy = *op;
    copy->tally = pst_tally_start(tally, &op->opts.progress, total);
    return copy;
}

/* 1 when the scheme's derivatives read the rows' data and op has none: after a failed
 * pst_op_refresh (a created operator skips the rows only where the derivatives do not read
 * them). */
static int rows_lost(const pst_op *op) { return !op->rows && !op->scheme->derivatives_standalone; }

/* A derivative hook of the scheme (gradient or Hessian) at every particle, with the packed
 * values and the progress view the applies have. */
typedef void (*derivative_fn)(const pst_op *op, const double *u, double *const out[]);

static int run_derivative(const pst_op *op, derivative_fn hook, const double *u,
                          double *const out[])
{
    if (!hook || op->half || rows_lost(op))
        return PST_EINVAL;
    if (op->xyzu)
        pack_values(op, u);
    pst_op copy;
    pst_tally tally;
    const pst_op *v = progress_view(op, op->n, &copy, &tally);
    hook(v, u, out);
    pst_tally_finish(v->tally);
    return PST_OK;
}

int pst_op_gradient(const pst_op *op, const double *u, double *const grad[3])
{
    return run_derivative(op, op->scheme->gradient, u, grad);
}

int pst_op_hessian(const pst_op *op, const double *u, double *const hess[6])
{
    return run_derivative(op, op->scheme->hessian, u, hess);
}

int pst_op_interpolate(const pst_op *op, const double *const pts[3], size_t m, const double *u,
                       double *value, double *lap, size_t *fallbacks, char *err)
{
    PST_CHECK(!op->scheme->interpolate, PST_EINVAL, err, "scheme %s has no interpolation",
              op->scheme->name);
    PST_CHECK(op->half, PST_EINVAL, err,
              "the operator uses a half list: interpolation needs the whole one");
    PST_CHECK(rows_lost(op), PST_EINVAL, err,
              "the operator has no rows (its refresh failed): create it again");
    size_t none = 0;
    pst_op copy;
    pst_tally tally;
    const pst_op *v = progress_view(op, m, &copy, &tally);
    int st = op->scheme->interpolate(v, pts, m, u, value, lap, fallbacks ? fallbacks : &none,
                                     err);
    if (st == PST_OK)
        pst_tally_finish(v->tally);
    return st;
}
