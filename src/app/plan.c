/* The planner (docs/running.md). Every decision here is one a user could make by
 * hand; the planner makes it from the scene so that a run computes only what its outputs need:
 *   - a constant mobility is a factor, not a per-particle array (no pairwise averaging);
 *   - an operator that only feeds gradients, Hessians or interpolation gets no Laplacian rows
 *     (for schemes whose derivative estimates do not use them);
 *   - stored weights only for solves (many applies), and only when they fit in memory;
 *   - CG only for a symmetrisable scheme without flux rows on a cloud not periodic along
 *     every axis, GMRES otherwise;
 *   - the memory estimate is checked before the cloud is generated. */
#include "plan.h"

#include "memory_avail.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define PLAN_PI 3.14159265358979323846

/* The AMG set-up's peak memory, fitted to bench_solve's resident memory at 3D 10^6 (qsfdi, radius
 * 1.3 h and 1.6 h: 710 and 1123 bytes per row at 15.3 and 26.6 entries; docs/solving.md). */
#define AMG_BYTES_PER_ENTRY 36.5
#define AMG_BYTES_PER_ROW 150.0

/* The shortest GMRES restart the planner chooses to fit the memory (AMG solves), and the
 * tighter AMG proxy radius (in h) it chooses where memory is short and the scheme's automatic
 * one (pst_scheme_amg_radius) is wider. */
#define PLAN_MIN_RESTART 20
#define PLAN_AMG_TIGHT_RADIUS 1.3

/* The ghosts of the largest Morton range of a cloud cut into parts of equal counts, against
 * the shell of the box model below (part_ghosts): 1.0-2.9 on 41^3 and 81^3 jittered lattices
 * cut into 2 to 64 parts, with the quintic's and the cubic's supports at h = 1.2 s0 (a range
 * is a union of Morton blocks of many sizes, and a cut of equal counts falls inside a block:
 * its faces are staircases of cells). Times this factor the estimate is 1.0-2.9 times the
 * ghosts (tests/test_plan.c): an upper estimate, as a memory check wants. */
#define PLAN_GHOST_FACTOR 2.9

/* The particles whose rows, list and solver vectors this process holds: the whole cloud on
 * one process, its largest part over several ranks. */
static double plan_rows(const pst_plan *p)
{
    return p->ranks > 1 ? (double)(p->part_owned + p->part_ghosts) : (double)p->particles;
}

/* The ghosts of the largest part when the n particles of a D-dimensional cloud are cut into
 * `ranks` Morton ranges, each holding the particles within `reach` spacings of it (the
 * support times the rings of ghosts the scheme reads, pst_scheme_halo). The model: the cloud
 * a cube, cut by k = ceil(log2 ranks) bisections taken along the axes in turn (as the Morton
 * key's bits are) into boxes of n / ranks particles; a box is grown by `reach` on each face
 * that borders another part (none along an axis never cut, one along an axis cut once, or two
 * on a periodic axis, two along an axis cut more often), and the grown box's shell, times
 * PLAN_GHOST_FACTOR, is the estimate. At most the particles the part does not own. */
static size_t part_ghosts(const pst_scene *s, size_t n, int ranks, size_t owned, double reach)
{
    const int D = s->dim;
    int k = 0;
    while ((1L << k) < ranks)
        ++k;
    /* 2^k boxes of the bisections' shape, each scaled to the n / ranks particles it owns */
    double side = pow((double)n, 1.0 / D) * pow((double)(1L << k) / ranks, 1.0 / D);
    double box = 1, grown = 1;
    for (int a = 0; a < D; ++a) {
        int cuts = k / D + (a < k % D);
        int faces = cuts == 0 ? 0 : cuts >= 2 || s->cloud.periodic[a] ? 2 : 1;
        double ext = side / (double)(1L << cuts);
        box *= ext;
        grown *= ext + faces * reach;
    }
    double ghosts = ceil(PLAN_GHOST_FACTOR * (grown - box));
    return ghosts < (double)(n - owned) ? (size_t)ghosts : n - owned;
}

size_t pst_plan_particles(const pst_scene *s)
{
    const sc_cloud *c = &s->cloud;
    if (c->source == SC_CLOUD_FILE)
        return 0;
    size_t n[3] = {1, 1, 1}, total = 1;
    for (int d = 0; d < s->dim; ++d) {
        double cells = round((c->hi[d] - c->lo[d]) / c->spacing);
        n[d] = cells < 0 ? 0 : (size_t)cells;
        if (c->source == SC_CLOUD_LATTICE && !c->periodic[d])
            n[d] += 1; /* nodes, both ends included (a periodic axis's hi end is its lo) */
        total *= n[d];
    }
    size_t faces = 0; /* cell-centred: one particle per boundary cell face, none periodic */
    for (int a = 0; a < s->dim && c->source == SC_CLOUD_CELL_CENTRED; ++a)
        if (!c->periodic[a] && n[a])
            faces += 2 * (total / n[a]);
    return total + faces;
}

/* Outputs a task adds to the cloud, in doubles per particle. */
static int task_fields(const sc_task *t, int dim)
{
    switch (t->type) {
    case SC_TASK_GRADIENT: return dim;
    case SC_TASK_HESSIAN: return dim == 2 ? 3 : 6;
    case SC_TASK_INTERPOLATE: return 0;
    case SC_TASK_DIFFUSE: /* u, and the previous step's L u or the solve's right-hand side */
        return 2;
    case SC_TASK_SOLVE: /* with groups also NAME_kind and NAME_normal_* (docs/boundaries.md) */
        return t->ngroups ? 2 + dim : 1;
    default: return 1;
    }
}

/* A diffuse task's implicit system I - theta dt L is a linear operator of its own (a pst_linop,
 * docs/time-stepping.md): neither symmetric (its Dirichlet rows are held) nor an engine
 * operator, which AMG needs; moving particles re-sample the mobility at their positions,
 * which a per-cell SPE10 field does not give. */
static int check_steps(const pst_scene *s, const sc_task *t, char *err, size_t errlen)
{
    const char *why = t->solver == PST_SOLVER_CG   ? "CG needs a symmetric operator, and I - "
                                                     "theta dt L with its held Dirichlet rows is "
                                                     "not: use gmres or bicgstab"
                      : t->precond == PST_PREC_AMG ? "AMG needs the engine operator's rows, and "
                                                     "I - theta dt L is a linear operator of its "
                                                     "own: use jacobi"
                      : t->nvelocity && s->mobility.type == SC_MOB_SPE10
                          ? "moving particles need a mobility of their positions: an SPE10 "
                            "layer is per cell of the start"
                          : NULL;
    if (!why)
        return PST_OK;
    snprintf(err, errlen, "task '%s': %s", t->name, why);
    return PST_EINPUT;
}

/* A task the scheme or the scene cannot take: bad input (exit 2, docs/cli.md). */
static int check_task(const pst_scene *s, int k, int mobility, char *err, size_t errlen)
{
    const sc_task *t = &s->tasks[k];
    const char *scheme = s->op.scheme;
    int need = t->type == SC_TASK_GRADIENT      ? PST_SUPPORTS_GRADIENT
               : t->type == SC_TASK_HESSIAN     ? PST_SUPPORTS_HESSIAN
               : t->type == SC_TASK_INTERPOLATE ? PST_SUPPORTS_INTERPOLATE
                                                : -1;
    if (need >= 0 && !pst_scheme_supports(scheme, need)) {
        snprintf(err, errlen, "task '%s': scheme '%s' has no %s", t->name, scheme,
                 need == PST_SUPPORTS_GRADIENT  ? "gradient"
                 : need == PST_SUPPORTS_HESSIAN ? "Hessian"
                                                : "interpolation");
        return PST_EINPUT;
    }
    if (t->type == SC_TASK_DIVERGENCE && s->mobility.type == SC_MOB_NONE) {
        snprintf(err, errlen, "task '%s': a divergence task needs a mobility (mobility.type)",
                 t->name);
        return PST_EINPUT;
    }
    if (t->type == SC_TASK_LAPLACIAN && s->mobility.type != SC_MOB_NONE) {
        snprintf(err, errlen, "task '%s': the scene has a mobility, so its operator is "
                              "div(M grad u): use type 'divergence'", t->name);
        return PST_EINPUT;
    }
    if (mobility && (t->type == SC_TASK_DIVERGENCE || t->type == SC_TASK_SOLVE ||
                     t->type == SC_TASK_DIFFUSE) &&
        !pst_scheme_supports(scheme, PST_SUPPORTS_MOBILITY)) {
        snprintf(err, errlen, "task '%s': scheme '%s' discretises the plain Laplacian only; "
                              "a variable mobility needs another scheme (e.g. lv)",
                 t->name, scheme);
        return PST_EINPUT;
    }
    if (t->type == SC_TASK_DIFFUSE)
        return check_steps(s, t, err, errlen);
    if (t->type == SC_TASK_SOLVE && t->solver == PST_SOLVER_CG) {
        int neumann = 0;
        for (int g = 0; g < t->ngroups; ++g)
            neumann |= t->groups[g].neumann;
        if (neumann || !pst_scheme_supports(scheme, PST_SUPPORTS_SYMMETRIC) ||
            (s->op.gradient != PST_GRAD_G1 && s->op.gradient != 0)) {
            snprintf(err, errlen, "task '%s': CG needs a symmetrisable operator (brookshaw or "
                                  "cb with gradient G1 and no Neumann rows); use gmres",
                     t->name);
            return PST_EINPUT;
        }
    }
    return PST_OK;
}

/* 1 when task k's AMG matrix is the Brookshaw proxy (amg_source brookshaw, or auto on a scheme
 * that does not name its own matrix), 0 for the scheme's own stencil. */
static int amg_uses_proxy(const pst_plan *p, const pst_scene *s, int k)
{
    int source = p->task_amg_source[k];
    return source == PST_AMG_BROOKSHAW ||
           (source == PST_AMG_AUTO && !pst_scheme_amg_own(s->op.scheme));
}

/* Entries per row of task k's AMG matrix: the Brookshaw proxy's pairs within its radius (or
 * the whole list), or the scheme's own stencil (the list for every scheme but the mixed ones),
 * plus the diagonal. */
static double amg_entries_per_row(const pst_plan *p, const pst_scene *s, int k)
{
    /* the automatic radius (-1) is 1.6 h, or the whole list for a contrasted mobility, which
     * only the cloud shows: with a per-particle mobility the estimate assumes the whole list */
    double radius = p->task_amg_radius[k] >= 0 ? p->task_amg_radius[k]
                    : p->mobility_ncomp        ? 0
                                               : pst_scheme_amg_radius(s->op.scheme);
    double reach = p->support;
    if (amg_uses_proxy(p, s, k) && radius > 0 && radius < reach)
        reach = radius;
    reach *= p->h_ratio; /* in spacings */
    double pairs = s->dim == 2 ? PLAN_PI * reach * reach : 4.0 / 3.0 * PLAN_PI * pow(reach, 3);
    return fmax(pairs - 1, 1) + 1;
}

/* The AMG set-up's peak per row: bytes per AMG matrix entry and per row measured at the peak
 * (hypre's copy of the matrix, its strength graph, interpolation and coarse levels, with
 * pstencil's copy freed), docs/solving.md "Memory". */
static double amg_bytes_per_row(const pst_plan *p, const pst_scene *s)
{
    double most = 0;
    for (int k = 0; k < s->ntasks; ++k)
        if (s->tasks[k].type == SC_TASK_SOLVE && p->task_precond[k] == PST_PREC_AMG)
            most = fmax(most, AMG_BYTES_PER_ENTRY * amg_entries_per_row(p, s, k) +
                                  AMG_BYTES_PER_ROW);
    return most;
}

/* Where the run would not fit in `budget` bytes, the AMG solves with amg_source auto on the
 * scheme's own matrix (lsmps: the whole list, about 160 entries per row in 3D) take the
 * Brookshaw proxy; where it still does not fit, those with a wider automatic radius (and no
 * per-particle mobility, whose contrast may need the whole list) take the tight one: in 3D
 * 1.3 h keeps about 15 entries per row against 25 at 1.6 h, for up to 40 % more iterations on
 * lv and lpmps (qsfdi's automatic radius is 1.3 h already; docs/solving.md). */
static void fit_amg_radius(pst_plan *p, const pst_scene *s, double other, double budget)
{
    double n = plan_rows(p);
    for (int k = 0; k < s->ntasks; ++k)
        if (other + n * amg_bytes_per_row(p, s) > budget && s->tasks[k].type == SC_TASK_SOLVE &&
            p->task_amg_source[k] == PST_AMG_AUTO && !amg_uses_proxy(p, s, k))
            p->task_amg_source[k] = PST_AMG_BROOKSHAW;
    if (other + n * amg_bytes_per_row(p, s) <= budget || p->mobility_ncomp)
        return;
    for (int k = 0; k < s->ntasks; ++k)
        if (s->tasks[k].type == SC_TASK_SOLVE && s->tasks[k].amg_radius < 0 &&
            amg_uses_proxy(p, s, k) && pst_scheme_amg_radius(s->op.scheme) > PLAN_AMG_TIGHT_RADIUS)
            p->task_amg_radius[k] = PLAN_AMG_TIGHT_RADIUS;
}

/* 1 when task k solves: a solve, or a diffuse task of an implicit method. */
static int task_solves(const pst_scene *s, int k)
{
    const sc_task *t = &s->tasks[k];
    return t->type == SC_TASK_SOLVE ||
           (t->type == SC_TASK_DIFFUSE && t->method != SC_METHOD_EXPLICIT);
}

/* Vectors of n doubles the largest solve holds: GMRES(m) m + 8 (the basis and the solver's
 * own), the other methods 8. */
static double solver_vectors(const pst_plan *p, const pst_scene *s)
{
    double v = 0;
    for (int k = 0; k < s->ntasks; ++k)
        if (task_solves(s, k))
            v = fmax(v, p->task_solver[k] == PST_SOLVER_GMRES ? p->task_restart[k] + 8 : 8);
    return v;
}

/* Where the Krylov vectors would not fit in `room` bytes, shorten the GMRES restarts of the
 * AMG solves (they converge in tens of iterations) down to PLAN_MIN_RESTART. */
static void fit_restarts(pst_plan *p, const pst_scene *s, double room)
{
    double n = plan_rows(p), room_vectors = floor(room / (8.0 * n)) - 8;
    if (!(room_vectors < INT_MAX)) /* no particles known yet, or room for any restart */
        return;
    int fits = (int)room_vectors;
    for (int k = 0; k < s->ntasks; ++k)
        if (s->tasks[k].type == SC_TASK_SOLVE && p->task_solver[k] == PST_SOLVER_GMRES &&
            p->task_precond[k] == PST_PREC_AMG && p->task_restart[k] > fits)
            p->task_restart[k] = fits > PLAN_MIN_RESTART ? fits : PLAN_MIN_RESTART;
}

/* What the base operator keeps for the gradient and Hessian tasks it serves (pst_op_opts.keep):
 * the weights its precompute's inversions give, so that each task is one pass over the
 * neighbours instead of a second precompute. Only with Laplacian rows: a derivatives-only
 * operator computes them in its one pass anyway. */
static int base_keep(const pst_plan *p, const pst_scene *s)
{
    if (!p->base_operator || !p->base_laplacian ||
        !pst_scheme_supports(s->op.scheme, PST_SUPPORTS_KEEP))
        return 0;
    int keep = 0;
    for (int k = 0; k < s->ntasks; ++k)
        keep |= s->tasks[k].type == SC_TASK_GRADIENT  ? PST_KEEP_GRADIENT
                : s->tasks[k].type == SC_TASK_HESSIAN ? PST_KEEP_HESSIAN
                                                      : 0;
    return keep;
}

/* The half list (pst_op_use_half_list) serves a run whose one operator feeds only matrix-free
 * solves and Laplacian or divergence applies, of a scheme with a half-list apply, and whose AMG
 * solves use the Brookshaw proxy in the whole-list plan (the scheme's own matrix needs whole
 * rows, and where it fits it serves better than any list layout: lsmps). */
static int half_list_serves(const pst_plan *p, const pst_scene *s, int nops)
{
    if (nops != 1 || (p->base_operator && !p->base_laplacian) ||
        !pst_scheme_supports(s->op.scheme, PST_SUPPORTS_HALF_LIST))
        return 0;
    for (int k = 0; k < s->ntasks; ++k) {
        const sc_task *t = &s->tasks[k];
        if (t->type == SC_TASK_SOLVE) {
            if (p->task_stored[k] || p->task_petsc[k] || /* PETSc takes the whole rows */
                (p->task_precond[k] == PST_PREC_AMG && !amg_uses_proxy(p, s, k)))
                return 0;
        } else if (t->type != SC_TASK_LAPLACIAN && t->type != SC_TASK_DIVERGENCE) {
            return 0;
        }
    }
    return 1;
}

/* 1 when the whole-list plan gives something up to fit `budget`: it does not fit, or a solve
 * had its restart shortened, its AMG radius tightened or its AMG matrix changed. Only then does
 * the half list pay: the whole-list matrix-free apply is faster (a half-list pair costs about
 * three whole-list pairs: two weights, the other row's coefficients, the scatter), 1.4-1.8x
 * in 3D (docs/operators.md, "The half-list apply"). */
static int whole_list_gives_up(const pst_plan *p, const pst_scene *s, double budget)
{
    if (p->bytes_total > budget)
        return 1;
    for (int k = 0; k < s->ntasks; ++k) {
        const sc_task *t = &s->tasks[k];
        if (t->type == SC_TASK_SOLVE &&
            (p->task_restart[k] < t->restart || p->task_amg_radius[k] != t->amg_radius ||
             p->task_amg_source[k] != t->amg_source))
            return 1;
    }
    return 0;
}

/* Fit the solves into `budget` with a list of `list` bytes resident during them: the AMG
 * matrix and radius, the restarts and the stored weights, from the scene's own settings. On a
 * half list (half = 1) no weights are stored and AMG AUTO takes the Brookshaw proxy, as the
 * library does. Fills bytes_solver and bytes_weights; returns the bytes of the solve phase. */
static double fit_solves(pst_plan *p, const pst_scene *s, double list, double budget, int half)
{
    double n = plan_rows(p);
    for (int k = 0; k < s->ntasks; ++k) {
        p->task_restart[k] = s->tasks[k].restart;
        p->task_amg_radius[k] = s->tasks[k].amg_radius;
        int own = s->tasks[k].amg_source == PST_AMG_AUTO && pst_scheme_amg_own(s->op.scheme);
        p->task_amg_source[k] = half && own ? PST_AMG_BROOKSHAW : s->tasks[k].amg_source;
    }
    double other = p->bytes_cloud + list + p->bytes_operators;
    fit_amg_radius(p, s, other + n * 8.0 * solver_vectors(p, s), budget);
    double amg = amg_bytes_per_row(p, s), fixed = other + n * amg;
    fit_restarts(p, s, budget - fixed);
    p->bytes_solver = n * (8.0 * solver_vectors(p, s) + amg);
    double without = fixed + n * 8.0 * solver_vectors(p, s);
    /* Weights pay off for solves and time steps (hundreds of applies); a single apply is
     * cheaper without. */
    p->bytes_weights = 0;
    for (int k = 0; k < s->ntasks; ++k) {
        const sc_task *t = &s->tasks[k];
        if (t->type != SC_TASK_SOLVE && t->type != SC_TASK_DIFFUSE)
            continue;
        double w = (t->stored == SC_OPERATOR_STORED_FLOAT ? 4.0 : 8.0) * n * p->neighbours;
        p->task_stored[k] = half || p->task_petsc[k] ? SC_OPERATOR_MATRIX_FREE /* MatShell */
                            : t->stored != SC_OPERATOR_AUTO ? (int)t->stored
                            : without + p->bytes_weights + w <= budget
                                ? SC_OPERATOR_STORED
                                : SC_OPERATOR_MATRIX_FREE;
        if (p->task_stored[k])
            p->bytes_weights += w;
    }
    return without + p->bytes_weights;
}

/* The refusal of a plan over its budget: PST_ENOMEM, with the estimate in err. */
static int refuse_memory(const pst_plan *p, const pst_scene *s, char *err, size_t errlen)
{
    char share[96] = "";
    if (p->node_ranks > 1)
        snprintf(share, sizeof share, "this rank's share, 1/%d, of ", p->node_ranks);
    snprintf(err, errlen, "the run needs about %.2f GB%s (cloud %.2f, neighbours %.2f, "
                          "half list %.2f, operators %.2f, weights %.2f, solver %.2f), more "
                          "than %.0f %% of %sthe %.2f GB available (limits.memory_fraction; "
                          "the limit that applies: %s); use a coarser spacing%s or fewer "
                          "tasks",
             p->bytes_total * 1e-9, p->ranks > 1 ? " per rank" : "", p->bytes_cloud * 1e-9,
             p->bytes_neighbours * 1e-9, p->bytes_half_list * 1e-9,
             p->bytes_operators * 1e-9, p->bytes_weights * 1e-9, p->bytes_solver * 1e-9,
             100 * s->memory_fraction, share, p->bytes_available * 1e-9, p->memory_limit,
             p->ranks > 1 ? ", more nodes" : "");
    return PST_ENOMEM;
}

/* The refusal of a solve that the plan puts in PETSc when the library has no PETSc: the run
 * would stop when it starts PETSc (with --petsc, after building the cloud and the operator),
 * and --plan would show a solve that cannot run. */
static int refuse_petsc(const pst_plan *p, const sc_task *t, char *err, size_t errlen)
{
    snprintf(err, errlen, "task '%s' solves in PETSc (%s), but this pstencil was built without "
                          "it ('pstencil sysinfo' says so): solve on one process without "
                          "PETSc, or build pstencil with petsc-dev installed",
             t->name, p->ranks > 1 ? "over mpirun's ranks"
                      : t->petsc   ? "tasks[].petsc"
                                   : "--petsc");
    return PST_EINVAL;
}

/* The plan for `particles` particles with h = h_ratio s0, run where w says (NULL: one
 * process). */
static int plan_make(pst_plan *p, const pst_scene *s, size_t particles, double h_ratio,
                     const pst_plan_where *w, char *err, size_t errlen)
{
    memset(p, 0, sizeof *p);
    int bad = pst_scene_compile_exprs(s, err, errlen);
    if (bad != PST_OK)
        return bad;
    const int dim = s->dim;
    p->particles = particles;
    p->h_ratio = h_ratio;
    p->ranks = w && w->ranks > 1 ? w->ranks : 1;
    p->node_ranks = p->ranks == 1                                   ? 1
                    : w->node_ranks >= 1 && w->node_ranks <= p->ranks ? w->node_ranks
                                                                      : p->ranks;
    p->kernel = s->op.kernel >= 0 ? s->op.kernel : pst_scheme_default_kernel(s->op.scheme);
    p->support = pst_kernel_support(p->kernel);
    double reach = p->support * p->h_ratio; /* in spacings */
    /* 0 for a file cloud not read yet (h_ratio 0) */
    p->neighbours =
        fmax((dim == 2 ? PLAN_PI * reach * reach : 4.0 / 3.0 * PLAN_PI * pow(reach, 3)) - 1, 0);

    p->mobility_factor = 1;
    switch (s->mobility.type) {
    case SC_MOB_CONSTANT: p->mobility_factor = s->mobility.value; break;
    case SC_MOB_EXPR: p->mobility_ncomp = s->mobility.ncomp; break;
    case SC_MOB_SPE10: p->mobility_ncomp = dim; break;
    default: break;
    }

    /* per particle: x, V, normals, id, the fields, the mobility (task outputs below) */
    double doubles = dim + 1 + dim + 1 + s->nfields + p->mobility_ncomp;
    for (int k = 0; k < s->ntasks; ++k) {
        const sc_task *t = &s->tasks[k];
        int st = check_task(s, k, p->mobility_ncomp > 0, err, errlen);
        if (st != PST_OK)
            return st;
        doubles += task_fields(t, dim);
        p->need_neighbours = 1;
        if (t->type != SC_TASK_SOLVE || t->ngroups == 0) {
            p->base_operator = 1;
            if (t->type == SC_TASK_LAPLACIAN || t->type == SC_TASK_DIVERGENCE ||
                t->type == SC_TASK_SOLVE || t->type == SC_TASK_DIFFUSE ||
                !pst_scheme_supports(s->op.scheme, PST_SUPPORTS_DERIVATIVES_ONLY))
                p->base_laplacian = 1;
        }
        if (t->type == SC_TASK_DIFFUSE) {
            p->task_solver[k] = t->solver != PST_SOLVER_AUTO ? t->solver : PST_SOLVER_GMRES;
            p->task_precond[k] = t->precond != SC_PRECOND_AUTO ? t->precond : PST_PREC_JACOBI;
            p->moving |= t->nvelocity > 0;
            p->skin = t->nvelocity ? t->skin : p->skin;
        }
        if (t->type == SC_TASK_SOLVE) {
            p->task_petsc[k] = p->ranks > 1 || (w && w->petsc) || t->petsc;
            if (p->task_petsc[k] && !pst_petsc_available())
                return refuse_petsc(p, t, err, errlen);
            int neumann = 0;
            for (int g = 0; g < t->ngroups; ++g)
                neumann |= t->groups[g].neumann;
            /* periodic along every axis, the mean is most likely fixed, which CG cannot do */
            int symmetric = pst_scheme_supports(s->op.scheme, PST_SUPPORTS_SYMMETRIC) &&
                            (s->op.gradient == PST_GRAD_G1 || s->op.gradient == 0) && !neumann &&
                            pst_scene_periodic_axes(s) < dim;
            p->task_solver[k] = t->solver != PST_SOLVER_AUTO ? t->solver
                                : symmetric                  ? PST_SOLVER_CG
                                                             : PST_SOLVER_GMRES;
            p->task_precond[k] = t->precond != SC_PRECOND_AUTO ? t->precond
                                 : pst_have_amg()              ? PST_PREC_AMG
                                                               : PST_PREC_JACOBI;
        }
    }
    p->bytes_cloud = (double)particles * (8.0 * doubles + 1);
    if (p->ranks > 1) { /* every rank builds the whole cloud, then its part (positions, V,
                           normals, ids, mobility, kinds) */
        p->part_owned = (particles + (size_t)p->ranks - 1) / (size_t)p->ranks;
        p->part_ghosts = part_ghosts(s, particles, p->ranks, p->part_owned,
                                     reach * pst_scheme_halo(s->op.scheme));
        p->bytes_cloud += plan_rows(p) * (8.0 * (2 * dim + 2 + p->mobility_ncomp) + 1);
    }
    double n = plan_rows(p);
    p->bytes_neighbours = p->need_neighbours ? n * (8.0 + 4.0 * p->neighbours) : 0;
    int nops = p->base_operator;
    for (int k = 0; k < s->ntasks; ++k)
        nops += s->tasks[k].type == SC_TASK_SOLVE && s->tasks[k].ngroups > 0;
    /* the scheme's per-particle data, the row status and the packed rows of the lane schemes
     * (kept on a half list, whose lane rows read them too) */
    const double packed = n * pst_scheme_apply_bytes(s->op.scheme);
    p->bytes_operators = nops * (n * (1.0 + pst_scheme_data_bytes(s->op.scheme, dim)) + packed);
    pst_memory_avail avail;
    pst_memory_probe(&avail);
    p->bytes_available = avail.bytes;
    p->memory_limit = avail.limit;
    double budget = s->memory_fraction * p->bytes_available / p->node_ranks;
    p->base_keep = base_keep(p, s);
    p->bytes_total = fit_solves(p, s, p->bytes_neighbours, budget, 0);
    double kept = n * pst_scheme_keep_bytes(s->op.scheme, dim, p->base_keep);
    if (p->bytes_total + kept > budget)
        p->base_keep = 0; /* the derivatives are then computed when asked */
    else
        p->bytes_operators += kept;
    p->bytes_total = fit_solves(p, s, p->bytes_neighbours, budget, 0);
    if (half_list_serves(p, s, nops) && whole_list_gives_up(p, s, budget)) {
        /* matrix-free and short of memory: the half list is smaller; the whole list lives
         * through the precompute and the copy only */
        p->half_list = 1;
        p->bytes_half_list = n * (8.0 + 2.0 * p->neighbours);
        double solves = fit_solves(p, s, p->bytes_half_list, budget, 1);
        p->bytes_total = fmax(solves, p->bytes_cloud + p->bytes_neighbours +
                                          p->bytes_half_list + p->bytes_operators);
    }
    if (p->bytes_total > budget)
        return refuse_memory(p, s, err, errlen);
    return PST_OK;
}

int pst_plan_make(pst_plan *p, const pst_scene *s, size_t particles, const pst_plan_where *w,
                  char *err, size_t errlen)
{
    return plan_make(p, s, particles, s->cloud.source == SC_CLOUD_FILE ? 0 : s->cloud.h_ratio, w,
                     err, errlen);
}

int pst_plan_make_for_cloud(pst_plan *p, const pst_scene *s, const pst_cloud *c,
                            const pst_plan_where *w, char *err, size_t errlen)
{
    size_t n = pst_cloud_size(c);
    const double *V = pst_cloud_volume_const(c), *h = pst_cloud_h_array(c);
    double sum = 0, e = 1.0 / pst_cloud_dim(c), hu = pst_cloud_h_uniform(c);
    for (size_t i = 0; i < n; ++i)
        sum += (h ? h[i] : hu) / pow(V[i], e);
    return plan_make(p, s, n, n ? sum / (double)n : 0, w, err, errlen);
}

static const char *task_type_name(int type)
{
    static const char *const names[] = {"laplacian", "divergence", "gradient",
                                        "hessian",   "interpolate", "solve", "diffuse"};
    return names[type];
}

static const char *solver_name(int s)
{
    static const char *const names[] = {"auto", "CG", "GMRES", "BiCGSTAB"};
    return names[s];
}

static const char *precond_name(int p)
{
    static const char *const names[] = {"none", "Jacobi", "AMG (hypre BoomerAMG)"};
    return names[p];
}

/* How a task's plan applies L (pst_plan.task_stored). */
static const char *operator_use_name(int stored)
{
    static const char *const names[] = {"matrix-free", "stored", "stored (float)"};
    return names[stored];
}

static void print_solve(FILE *f, const pst_plan *p, int k, const sc_task *t)
{
    fprintf(f, ": %s", solver_name(p->task_solver[k]));
    if (p->task_solver[k] == PST_SOLVER_GMRES)
        fprintf(f, "(%d)%s", p->task_restart[k],
                p->task_restart[k] < t->restart ? " (restart shortened to fit)" : "");
    fprintf(f, " + %s", precond_name(p->task_precond[k]));
    if (p->task_precond[k] == PST_PREC_AMG && p->task_amg_source[k] != t->amg_source)
        fprintf(f, " on the Brookshaw proxy (to fit)");
    if (p->task_precond[k] == PST_PREC_AMG && p->task_amg_radius[k] != t->amg_radius)
        fprintf(f, " on pairs within %g h (to fit)", p->task_amg_radius[k]);
    fprintf(f, ", rtol %g, %s operator%s", t->rtol,
            operator_use_name(p->task_stored[k]), t->ngroups ? ", own boundary groups" : "");
    if (p->task_petsc[k] && p->ranks > 1)
        fprintf(f, ", in PETSc over %d ranks", p->ranks);
    else if (p->task_petsc[k])
        fprintf(f, ", in PETSc");
}

static void print_steps(FILE *f, const pst_plan *p, int k, const sc_task *t)
{
    static const char *const methods[] = {"forward Euler", "backward Euler", "Crank-Nicolson"};
    fprintf(f, ": %s to t = %g, ", methods[t->method], t->t_end);
    if (t->dt > 0)
        fprintf(f, "dt %g", t->dt);
    else
        fprintf(f, "dt %g of the step limit", t->safety);
    if (t->method != SC_METHOD_EXPLICIT)
        fprintf(f, ", %s + %s, rtol %g", solver_name(p->task_solver[k]),
                precond_name(p->task_precond[k]), t->rtol);
    fprintf(f, ", %s operator%s", operator_use_name(p->task_stored[k]),
            t->nvelocity ? ", moving particles" : "");
}

void pst_plan_print(FILE *f, const pst_plan *p, const pst_scene *s)
{
    fprintf(f, "plan for %s%s%s\n", s->path, s->title ? ": " : "", s->title ? s->title : "");
    if (s->cloud.source != SC_CLOUD_FILE)
        fprintf(f, "  cloud      %dD, %zu particles, h = %g s0\n", s->dim, p->particles,
                p->h_ratio);
    else if (p->particles)
        fprintf(f, "  cloud      %dD, %zu particles from %s, h = %.3g s0 (mean h / V^(1/%d))\n",
                s->dim, p->particles, s->cloud.file, p->h_ratio, s->dim);
    if (p->ranks > 1)
        fprintf(f, "  ranks      %d (%d on this node), each with its part of the cloud: about %zu "
                   "owned and %zu ghost particles (estimated); the memory below is one rank's\n",
                p->ranks, p->node_ranks, p->part_owned, p->part_ghosts);
    if (pst_scene_periodic_axes(s)) {
        fprintf(f, "  periodic  ");
        for (int d = 0; d < s->dim; ++d)
            if (s->cloud.periodic[d])
                fprintf(f, " %c", "xyz"[d]);
        fprintf(f, " (a solve without Dirichlet particles fixes the mean of u)\n");
    }
    if (p->mobility_ncomp)
        fprintf(f, "  mobility   %s per particle\n",
                p->mobility_ncomp == 1 ? "scalar" : "diagonal tensor");
    else if (s->mobility.type == SC_MOB_CONSTANT)
        fprintf(f, "  mobility   constant %g: a factor on L, no per-particle array\n",
                p->mobility_factor);
    if (p->need_neighbours)
        fprintf(f, "  neighbours kernel %s, support %gh, about %.0f per particle%s\n",
                pst_kernel_name(p->kernel), p->support, p->neighbours,
                p->half_list ? "; a half list (each pair once) after the precompute" : "");
    if (p->base_operator)
        fprintf(f, "  operator   %s%s%s%s\n", s->op.scheme,
                p->base_laplacian ? "" : ", derivatives only (no Laplacian rows)",
                p->base_keep ? "; keeps the weights of its " : "",
                p->base_keep == (PST_KEEP_GRADIENT | PST_KEEP_HESSIAN) ? "gradient and Hessian"
                : p->base_keep == PST_KEEP_GRADIENT                     ? "gradient"
                : p->base_keep                                          ? "Hessian"
                                                                        : "");
    for (int k = 0; k < s->ntasks; ++k) {
        const sc_task *t = &s->tasks[k];
        fprintf(f, "  task %-6d %s '%s'", k, task_type_name(t->type), t->name);
        if (t->type == SC_TASK_DIFFUSE)
            print_steps(f, p, k, t);
        else if (t->type == SC_TASK_SOLVE)
            print_solve(f, p, k, t);
        else if (t->field)
            fprintf(f, " of %s", t->field);
        if (t->nexact && t->nnorms)
            fprintf(f, ", %d error norm%s", t->nnorms, t->nnorms > 1 ? "s" : "");
        fprintf(f, "\n");
    }
    /* GB for big runs, MB for small ones, so that no part prints as 0.00 */
    int gb = p->bytes_total >= 1e9;
    double unit = gb ? 1e-9 : 1e-6;
    fprintf(f, "  memory     about %.2f %s (cloud %.2f, neighbours %.2f", p->bytes_total * unit,
            gb ? "GB" : "MB", p->bytes_cloud * unit, p->bytes_neighbours * unit);
    if (p->half_list)
        fprintf(f, ", half list %.2f", p->bytes_half_list * unit);
    fprintf(f, ", operators %.2f, weights %.2f, solver %.2f) of %.2f GB available",
            p->bytes_operators * unit, p->bytes_weights * unit, p->bytes_solver * unit,
            p->bytes_available * 1e-9);
    if (p->node_ranks > 1)
        fprintf(f, " to the %d ranks on this node", p->node_ranks);
    fprintf(f, " (%s)\n", p->memory_limit);
}
