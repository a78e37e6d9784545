/* The parameter table of scene files: every key once, with its type, default, units, range,
 * the task (or cloud, mobility) types it applies to and one sentence of documentation. The
 * loader (scene.c) checks scenes against it; `pstencil help scene` and docs/scenes.md are
 * printed from it here, so the documentation cannot drift from what is accepted. */
#include "scene.h"

#include <stdio.h>
#include <string.h>

#define FIELD_TASKS "laplacian|divergence|gradient|hessian|interpolate"
#define GENERATED "lattice|cell_centred"

/* Designated initialisers keep each row readable; unnamed members are 0 / NULL. */
const sc_param sc_params[] = {
    {.key = "title", .type = SC_T_STRING,
     .doc = "A one-line description printed in reports (default: the scene file's path)."},
    {.key = "dim", .type = SC_T_INT, .values = "2|3", .def = "2",
     .doc = "Dimension of the cloud; every vector in the scene has this many components."},

    {.key = "cloud", .type = SC_T_OBJECT, .doc = "The particle cloud."},
    {.key = "cloud.source", .type = SC_T_ENUM, .values = "lattice|cell_centred|file",
     .def = "\"lattice\"", .flags = SC_F_SELECTOR,
     .doc = "A jittered node lattice, the Lukyanov-Vuik cell-centred layout with face "
            "particles, or a CSV file (docs/clouds.md)."},
    {.key = "cloud.file", .type = SC_T_PATH, .applies = "file", .flags = SC_F_REQUIRED,
     .doc = "The cloud, read by its extension: .csv, or VTK XML .vtu / .vtp (docs/io.md); "
            "another extension is refused. Relative to the scene file's folder."},
    {.key = "cloud.lo", .type = SC_T_VEC, .def = "0", .units = "length", .applies = GENERATED,
     .doc = "Lower corner of the box."},
    {.key = "cloud.hi", .type = SC_T_VEC, .def = "1", .units = "length", .applies = GENERATED,
     .doc = "Upper corner of the box; hi - lo must be a whole number of spacings on every "
            "axis."},
    {.key = "cloud.periodic", .type = SC_T_AXES, .def = "false",
     .doc = "Periodic axes: true (every axis), false, or a list of dim booleans (x, y[, z]). "
            "Along a periodic axis the box wraps around: a generated cloud has no hi end node, "
            "boundary layer or face particles there (it cannot be rotated), a file cloud needs "
            "cloud.box, and boundary groups have no side there. A solve without Dirichlet "
            "particles then fixes the mean of u (docs/periodic.md)."},
    {.key = "cloud.box", .type = SC_T_OBJECT, .applies = "file",
     .doc = "The periodic box {lo, hi} of a file cloud, required when an axis is periodic and "
            "refused otherwise (a generated cloud's box is cloud.lo, cloud.hi). Its periodic "
            "axes have period hi - lo; every particle must lie in [lo, hi) along them."},
    {.key = "cloud.box.lo", .type = SC_T_VEC, .units = "length", .flags = SC_F_REQUIRED,
     .doc = "Lower corner of the periodic box."},
    {.key = "cloud.box.hi", .type = SC_T_VEC, .units = "length", .flags = SC_F_REQUIRED,
     .doc = "Upper corner of the periodic box (read on the periodic axes; > lo on every "
            "axis)."},
    {.key = "cloud.spacing", .type = SC_T_REAL, .def = "0.05", .units = "length",
     .lo_kind = '(', .lo = 0,
     .doc = "Lattice spacing s0; for a file cloud it only scales h_ratio (when both are "
            "given, h = h_ratio*spacing for every particle)."},
    {.key = "cloud.jitter", .type = SC_T_REAL, .def = "0", .units = "s0", .lo_kind = '[',
     .lo = 0, .hi = 1, .hi_kind = ')', .applies = GENERATED,
     .doc = "K: each coordinate of a jittered particle moves by K*delta*s0, delta uniform in "
            "[-1, 1]."},
    {.key = "cloud.seed", .type = SC_T_INT, .def = "1", .lo_kind = '[', .lo = 0,
     .applies = GENERATED,
     .doc = "Seed of the counter-based jitter RNG (the same cloud for every thread count)."},
    {.key = "cloud.boundary_layer", .type = SC_T_BOOL, .def = "true", .applies = "lattice",
     .doc = "Keep the outer layer of the lattice unjittered and make it the Dirichlet "
            "boundary."},
    {.key = "cloud.angle", .type = SC_T_REAL, .def = "0", .units = "degrees", .lo_kind = '[',
     .lo = -360, .hi = 360, .hi_kind = ']', .applies = "lattice",
     .doc = "Rotation of the lattice about the box centre (3D: about the z axis)."},
    {.key = "cloud.h_ratio", .type = SC_T_REAL, .def = "1.2", .units = "s0", .lo_kind = '(',
     .lo = 0,
     .doc = "Smoothing length h = h_ratio*s0; a file cloud keeps its own h unless this is "
            "given, and then s0 is cloud.spacing if given, else each particle's V^(1/dim)."},

    {.key = "mobility", .type = SC_T_OBJECT,
     .doc = "The mobility M of div(M grad u) (tasks of type divergence and solve)."},
    {.key = "mobility.type", .type = SC_T_ENUM, .values = "none|constant|expression|spe10",
     .def = "\"none\"", .flags = SC_F_SELECTOR,
     .doc = "none (M = 1), a constant, expressions of x, y, z, or SPE10 permeability."},
    {.key = "mobility.value", .type = SC_T_REAL, .lo_kind = '(', .lo = 0,
     .applies = "constant", .flags = SC_F_REQUIRED, .doc = "The constant scalar mobility."},
    {.key = "mobility.expression", .type = SC_T_EXPRS, .applies = "expression",
     .flags = SC_F_REQUIRED,
     .doc = "A scalar mobility, or a list of dim expressions: the diagonal of a tensor."},
    {.key = "mobility.file", .type = SC_T_PATH, .applies = "spe10", .flags = SC_F_REQUIRED,
     .doc = "SPE10 permx.geos (layers 84, 85) or perm.txt (Tarbert), relative to the scene "
            "file's folder (docs/spe10.md)."},
    {.key = "mobility.layer", .type = SC_T_INT, .values = "0|84|85", .def = "85",
     .applies = "spe10", .doc = "The SPE10 layer: 84 or 85 (permx.geos), 0 (perm.txt)."},
    {.key = "mobility.i0", .type = SC_T_INT, .def = "0", .units = "cells", .lo_kind = '[',
     .lo = 0, .hi = 59, .hi_kind = ']', .applies = "spe10",
     .doc = "First cell along x of the block of the layer mapped onto the cloud's box."},
    {.key = "mobility.j0", .type = SC_T_INT, .def = "0", .units = "cells", .lo_kind = '[',
     .lo = 0, .hi = 219, .hi_kind = ']', .applies = "spe10",
     .doc = "First cell along y of that block."},

    {.key = "operator", .type = SC_T_OBJECT, .doc = "The discretisation."},
    {.key = "operator.scheme", .type = SC_T_ENUM, .def = "\"qsfdi\"",
     .doc = "A registered scheme (docs/operators.md)."},
    {.key = "operator.kernel", .type = SC_T_ENUM,
     .values = "default|cubic|quintic|wendland_c2|wendland_c4|wendland2|wendland4",
     .def = "\"default\"",
     .doc = "The smoothing kernel, named as on the command line; default is the scheme's own. "
            "wendland2 and wendland4 are older names of wendland_c2 and wendland_c4."},
    {.key = "operator.gradient", .type = SC_T_ENUM, .values = "G1|G2|G3|G4", .def = "\"G1\"",
     .doc = "Kernel-gradient variant of the Lukyanov-Vuik family (LV eqs. 15-18)."},
    {.key = "operator.variant", .type = SC_T_INT, .def = "0", .lo_kind = '[', .lo = 0,
     .hi = 2147483647.0, .hi_kind = ']',
     .doc = "Scheme variant (lsmps: 0 type B, 1 type A; 0 for the others)."},
    {.key = "operator.cond_max", .type = SC_T_REAL, .def = "1e10", .lo_kind = '(', .lo = 1,
     .doc = "Rows whose moment matrix has a larger condition estimate are flagged "
            "ill-conditioned."},
    {.key = "operator.rank_tol", .type = SC_T_REAL, .def = "1e-13", .lo_kind = '(', .lo = 0,
     .hi = 1, .hi_kind = ')',
     .doc = "Below 1/cond of rank_tol a moment matrix is rank-deficient and the row falls "
            "back (down the scheme's fallback chain: docs/operators.md)."},
    {.key = "operator.min_pair_distance", .type = SC_T_REAL, .def = "1e-8", .units = "h",
     .lo_kind = '(', .lo = 0, .hi = 0.5, .hi_kind = ')',
     .doc = "Pairs closer than this fraction of the smoothing length are degenerate and "
            "contribute nothing (near-duplicate particles)."},
    {.key = "operator.on_degenerate", .type = SC_T_ENUM, .values = "fall_back|refuse",
     .def = "\"fall_back\"",
     .doc = "Rows that are rank-deficient or have too few neighbours: take the next level of "
            "the scheme's fallback chain (flagged and counted), or refuse the operator (exit 3, "
            "naming the first such particle)."},
    {.key = "operator.mobility_mean", .type = SC_T_ENUM, .values = "arithmetic|harmonic",
     .def = "\"arithmetic\"",
     .doc = "Pair mobility of the Lukyanov-Vuik family: arithmetic m_I + m_J (the paper's) or "
            "twice the harmonic mean (TPFA's; for discontinuous, high-contrast mobility)."},

    {.key = "fields", .type = SC_T_OBJECT, .hi = SC_MAX_FIELDS, .hi_kind = ']',
     .doc = "Named input fields sampled at the particles."},
    {.key = "fields.<name>", .type = SC_T_EXPR,
     .doc = "A field: its name (a C identifier, not a CSV column name) and its expression of "
            "x, y, z."},

    {.key = "tasks", .type = SC_T_LIST, .item = SC_T_OBJECT, .hi = SC_MAX_TASKS,
     .hi_kind = ']', .doc = "What to compute, in order."},
    {.key = "tasks[].type", .type = SC_T_ENUM,
     .values = "laplacian|divergence|gradient|hessian|interpolate|solve|diffuse",
     .flags = SC_F_REQUIRED | SC_F_SELECTOR,
     .doc = "Laplacian, div(M grad u) with the scene's mobility, gradient, Hessian, "
            "interpolation at points, a solve of div(M grad u) = rhs, or du/dt = div(M grad u) "
            "+ source stepped in time (docs/time-stepping.md)."},
    {.key = "tasks[].name", .type = SC_T_STRING,
     .doc = "Name of the task's output field (a C identifier; default: the type, with _2, _3, "
            "... when repeated)."},
    {.key = "tasks[].field", .type = SC_T_STRING, .applies = FIELD_TASKS,
     .flags = SC_F_REQUIRED, .doc = "The input field, declared in fields."},
    {.key = "tasks[].exact", .type = SC_T_EXPRS,
     .doc = "The exact result: one expression, dim for a gradient, 3 (xx, yy, xy) or 6 (xx, "
            "yy, zz, xy, xz, yz) for a Hessian. The outputs then also hold NAME_exact and "
            "NAME_error (approx - exact) with the same components. A solve that fixes the mean "
            "of u (cloud.periodic) compares with the exact solution moved by a constant to u's "
            "V-weighted mean over all particles; the report gives the constant (exact_shift). "
            "A diffuse task's is of x, y, z and t, compared at t_end."},
    {.key = "tasks[].norms", .type = SC_T_LIST, .item = SC_T_ENUM,
     .values = "rel_l2|qsfdi11|qsfdi11_normalised|lv78|lv95|max_abs|max_rel",
     .hi = SC_NNORMS, .hi_kind = ']',
     .doc = "Error norms against exact (default with exact: rel_l2 and max_abs)."},
    {.key = "tasks[].region", .type = SC_T_ENUM_OR_OBJECT, .values = "interior|all",
     .def = "\"interior\"",
     .doc = "Where errors are measured: interior particles, all, or an object {lo, hi}. A "
            "laplacian or divergence task measures interior particles only (its boundary rows "
            "are not L u); the report gives the count (region_particles)."},
    {.key = "tasks[].region.lo", .type = SC_T_VEC, .units = "length", .flags = SC_F_REQUIRED,
     .doc = "Lower corner of the error box."},
    {.key = "tasks[].region.hi", .type = SC_T_VEC, .units = "length", .flags = SC_F_REQUIRED,
     .doc = "Upper corner of the error box."},
    {.key = "tasks[].points", .type = SC_T_OBJECT, .applies = "interpolate",
     .flags = SC_F_REQUIRED,
     .doc = "The interpolation points: {file} or a lattice {lo, hi, spacing}."},
    {.key = "tasks[].points.file", .type = SC_T_PATH,
     .doc = "A CSV file with x, y[, z] columns, relative to the scene file's folder."},
    {.key = "tasks[].points.lo", .type = SC_T_VEC, .units = "length",
     .doc = "Lower corner of the point lattice."},
    {.key = "tasks[].points.hi", .type = SC_T_VEC, .units = "length",
     .doc = "Upper corner of the point lattice."},
    {.key = "tasks[].points.spacing", .type = SC_T_REAL, .units = "length", .lo_kind = '(',
     .lo = 0, .doc = "Spacing of the point lattice."},
    {.key = "tasks[].rhs", .type = SC_T_EXPR, .applies = "solve", .flags = SC_F_REQUIRED,
     .doc = "Right-hand side g of div(M grad u) = g."},
    {.key = "tasks[].boundary", .type = SC_T_LIST, .item = SC_T_OBJECT, .applies = "solve",
     .hi = SC_MAX_GROUPS, .hi_kind = ']',
     .doc = "Boundary groups; a particle takes the first group that matches it, a group "
            "matching what all its selectors (kind, where, region) match (default: every "
            "boundary particle Dirichlet with u = exact; docs/boundaries.md)."},
    {.key = "tasks[].boundary[].where", .type = SC_T_ENUM,
     .values = "all|xlo|xhi|ylo|yhi|zlo|zhi", .def = "\"all\"",
     .doc = "Only the particles whose nearest side of the cloud's box is this one, or any."},
    {.key = "tasks[].boundary[].kind", .type = SC_T_ENUM,
     .values = "boundary|dirichlet|neumann|interior|any", .def = "\"boundary\"",
     .doc = "Only the particles of this kind in the cloud (its kind column): boundary is "
            "dirichlet or neumann; interior or any let a region turn cloud-interior particles "
            "into boundary ones."},
    {.key = "tasks[].boundary[].region", .type = SC_T_OBJECT,
     .doc = "Only the particles inside one region: a box {lo, hi}, a ball {center, radius}, a "
            "half-space {point, normal} (the side the normal points to, the plane included) "
            "or {expr} (where the expression is > 0)."},
    {.key = "tasks[].boundary[].region.lo", .type = SC_T_VEC, .units = "length",
     .doc = "Lower corner of the box."},
    {.key = "tasks[].boundary[].region.hi", .type = SC_T_VEC, .units = "length",
     .doc = "Upper corner of the box."},
    {.key = "tasks[].boundary[].region.center", .type = SC_T_VEC, .units = "length",
     .doc = "Centre of the ball."},
    {.key = "tasks[].boundary[].region.radius", .type = SC_T_REAL, .units = "length",
     .lo_kind = '(', .lo = 0, .doc = "Radius of the ball (its surface included)."},
    {.key = "tasks[].boundary[].region.point", .type = SC_T_VEC, .units = "length",
     .doc = "A point on the half-space's plane."},
    {.key = "tasks[].boundary[].region.normal", .type = SC_T_VEC,
     .doc = "The direction into the half-space (any length but zero)."},
    {.key = "tasks[].boundary[].region.expr", .type = SC_T_EXPR,
     .doc = "The region where this expression of x, y[, z] is > 0."},
    {.key = "tasks[].boundary[].type", .type = SC_T_ENUM, .values = "dirichlet|neumann",
     .def = "\"dirichlet\"", .doc = "u = value, or du/dn = value (outward normal)."},
    {.key = "tasks[].boundary[].normals", .type = SC_T_ENUM, .values = "file|face|estimate",
     .def = "\"file\"",
     .doc = "A neumann group's normals: the cloud's own (a particle without one takes its "
            "nearest box face's, counted in the report), the nearest box face's (the group's "
            "where side when given), or estimated from the Shepard sum "
            "(pst_normals_estimate, docs/boundaries.md)."},
    {.key = "tasks[].boundary[].value", .type = SC_T_EXPR, .flags = SC_F_REQUIRED,
     .doc = "The boundary value."},
    {.key = "tasks[].solver", .type = SC_T_ENUM, .values = "auto|cg|gmres|bicgstab",
     .def = "\"auto\"", .applies = "solve|diffuse",
     .doc = "Krylov method; auto is CG when the operator is symmetrisable, else GMRES (a "
            "diffuse task's: GMRES, and CG is refused). A solve that fixes the mean of u (a "
            "periodic cloud without Dirichlet particles) takes GMRES for auto and refuses cg."},
    {.key = "tasks[].precond", .type = SC_T_ENUM, .values = "none|jacobi|amg|auto",
     .def = "\"auto\"", .applies = "solve|diffuse",
     .doc = "Preconditioner; auto is AMG when pstencil is built with hypre, else Jacobi (a "
            "diffuse task's: Jacobi, and AMG is refused)."},
    {.key = "tasks[].amg_source", .type = SC_T_ENUM, .values = "brookshaw|own|auto",
     .def = "\"auto\"", .applies = "solve",
     .doc = "The matrix AMG is built on: the Brookshaw M-matrix, the scheme's own stencil, or "
            "the one the scheme names (auto: own for lsmps, Brookshaw for the others)."},
    {.key = "tasks[].amg_radius", .type = SC_T_REAL, .def = "-1", .lo_kind = '[', .lo = -1,
     .hi = 1000, .hi_kind = ']', .applies = "solve", .units = "h",
     .doc = "The Brookshaw AMG matrix keeps the pairs closer than this (0: every neighbour; "
            "-1: 1.3 for qsfdi, 1.6 for the others, 1.3 where memory is short, or every "
            "neighbour where the mobility varies more than tenfold)."},
    {.key = "tasks[].amg_aggressive", .type = SC_T_INT, .def = "0", .lo_kind = '[', .lo = 0,
     .hi = 10, .hi_kind = ']', .applies = "solve",
     .doc = "Levels of aggressive coarsening in the AMG hierarchy."},
    {.key = "tasks[].amg_strong", .type = SC_T_REAL, .def = "0", .lo_kind = '[', .lo = 0,
     .hi = 1, .hi_kind = ')', .applies = "solve",
     .doc = "AMG strong threshold (0: 0.25 in 2D, 0.5 in 3D)."},
    {.key = "tasks[].amg_coarsen", .type = SC_T_ENUM, .values = "hmis|pmis|falgout",
     .def = "\"hmis\"", .applies = "solve", .doc = "hypre's coarsening."},
    {.key = "tasks[].amg_interp", .type = SC_T_ENUM,
     .values = "ext_i|classical", .def = "\"ext_i\"", .applies = "solve",
     .doc = "hypre's interpolation: extended+i or classical modified."},
    {.key = "tasks[].amg_pmax", .type = SC_T_INT, .def = "4", .lo_kind = '[', .lo = 0,
     .hi = 100, .hi_kind = ']', .applies = "solve",
     .doc = "Interpolation entries kept per row (0: no truncation)."},
    {.key = "tasks[].petsc", .type = SC_T_STRING, .applies = "solve",
     .doc = "PETSc options of this solve, e.g. \"-ksp_type bcgs -pc_type jacobi\" (docs/"
            "distributed.md). Given, even empty, the solve runs in PETSc's KSP (GMRES(restart) "
            "+ BoomerAMG by default, rtol and max_iter as below); under mpirun with several "
            "ranks every solve does. Needs a pstencil built with PETSc."},
    {.key = "tasks[].restart", .type = SC_T_INT, .def = "50", .lo_kind = '[', .lo = 1,
     .hi = 2147483647.0, .hi_kind = ']', .applies = "solve|diffuse",
     .doc = "GMRES restart length."},
    {.key = "tasks[].max_iter", .type = SC_T_INT, .def = "5000", .lo_kind = '[', .lo = 1,
     .hi = 2147483647.0, .hi_kind = ']', .applies = "solve|diffuse", .doc = "Iteration limit."},
    {.key = "tasks[].rtol", .type = SC_T_REAL, .def = "1e-10", .lo_kind = '(', .lo = 0,
     .hi = 1, .hi_kind = ')', .applies = "solve|diffuse",
     .doc = "Stop when ||b - L u|| <= rtol ||b||."},
    {.key = "tasks[].operator", .type = SC_T_ENUM,
     .values = "auto|stored|matrix_free|stored_float", .def = "\"auto\"",
     .applies = "solve|diffuse",
     .doc = "Apply stored weights (8 bytes per pair) or matrix-free; auto lets the planner "
            "decide (stored where the weights fit in memory). stored_float keeps each weight "
            "in float (4 bytes per pair, 2^-24 relative): less memory and faster applies, L u "
            "within 1e-7 - 1e-6 of the double weights' (docs/operators.md); never chosen by "
            "auto."},
    {.key = "tasks[].initial", .type = SC_T_EXPR, .applies = "diffuse", .flags = SC_F_REQUIRED,
     .doc = "u at t = 0."},
    {.key = "tasks[].source", .type = SC_T_EXPR, .applies = "diffuse",
     .doc = "The source f of du/dt = div(M grad u) + f, of x, y, z and t (default 0)."},
    {.key = "tasks[].boundary_value", .type = SC_T_EXPR, .applies = "diffuse",
     .doc = "u at the cloud's Dirichlet particles, of x, y, z and t (default: exact)."},
    {.key = "tasks[].method", .type = SC_T_ENUM, .values = "explicit|implicit|crank_nicolson",
     .def = "\"implicit\"", .applies = "diffuse",
     .doc = "Forward Euler, backward Euler or Crank-Nicolson; the implicit ones solve (I - "
            "theta dt L) u = ... once per step with one solver handle."},
    {.key = "tasks[].t_end", .type = SC_T_REAL, .units = "time", .lo_kind = '(', .lo = 0,
     .applies = "diffuse", .flags = SC_F_REQUIRED, .doc = "The final time; steps start at 0."},
    {.key = "tasks[].dt", .type = SC_T_REAL, .units = "time", .lo_kind = '(', .lo = 0,
     .applies = "diffuse",
     .doc = "The time step, shortened so that whole steps end at t_end. Explicit: refused "
            "above the step limit 2/rho (rho the Gershgorin bound of L), default safety * "
            "2/rho; required by the implicit methods."},
    {.key = "tasks[].safety", .type = SC_T_REAL, .def = "0.9", .lo_kind = '(', .lo = 0, .hi = 1,
     .hi_kind = ']', .applies = "diffuse",
     .doc = "The explicit method's automatic step as a fraction of the limit 2/rho (not with "
            "dt)."},
    {.key = "tasks[].max_steps", .type = SC_T_INT, .def = "100000", .lo_kind = '[', .lo = 1,
     .hi = 1000000, .hi_kind = ']', .applies = "diffuse",
     .doc = "A run that needs more steps is refused before the first."},
    {.key = "tasks[].velocity", .type = SC_T_EXPRS, .applies = "diffuse",
     .doc = "dim expressions of x, y, z and t: each step moves the interior particles by dt v "
            "(the field moves with them), folds them into a periodic box and refreshes the "
            "list and the operator. The scene's only task then."},
    {.key = "tasks[].skin", .type = SC_T_REAL, .def = "0.3", .units = "h", .lo_kind = '[',
     .lo = 0, .hi = 3, .hi_kind = ']', .applies = "diffuse",
     .doc = "The Verlet skin of the moving particles' neighbour list (with velocity; at most "
            "the kernel's support): the list is rebuilt only when they moved further."},
    {.key = "tasks[].pvd", .type = SC_T_PATH, .applies = "diffuse",
     .doc = "The time series: a .pvd listing one VTU of the cloud per output step, named "
            "STEM_STEP.vtu beside it."},
    {.key = "tasks[].output_every", .type = SC_T_INT, .def = "10", .lo_kind = '[', .lo = 1,
     .hi = 1000000, .hi_kind = ']', .applies = "diffuse",
     .doc = "A VTU of the series every this many steps, and at the first and the last (with "
            "pvd; at most 10000 files)."},
    {.key = "tasks[].steps_csv", .type = SC_T_PATH, .applies = "diffuse",
     .doc = "One row per step: time, step, its timings (neighbours, refresh, apply, solve), "
            "the list rebuilt or not, iterations, rho, max |u|."},

    {.key = "outputs", .type = SC_T_OBJECT,
     .doc = "What to write; paths are relative to the working directory."},
    {.key = "outputs.csv", .type = SC_T_PATH, .doc = "The cloud and the fields as CSV."},
    {.key = "outputs.vtu", .type = SC_T_PATH,
     .doc = "The same for ParaView: .vtu (UnstructuredGrid) or .vtp (PolyData), gradients as "
            "3-component and Hessians as 6-component arrays, with the row status; another "
            "extension is refused (docs/io.md)."},
    {.key = "outputs.vtu_compress", .type = SC_T_BOOL, .def = "false",
     .doc = "Compress the vtu's arrays with zlib (VTK's vtkZLibDataCompressor)."},
    {.key = "outputs.report", .type = SC_T_PATH,
     .doc = "The run as JSON: sizes, timings, solver results and error norms."},
    {.key = "outputs.fields", .type = SC_T_LIST, .item = SC_T_STRING, .hi = SC_MAX_FIELDS,
     .hi_kind = ']',
     .doc = "The fields and task outputs written to csv and vtu (default: all of them); a "
            "task's name selects all its fields, NAME_exact and NAME_error included."},

    {.key = "limits", .type = SC_T_OBJECT, .doc = "Resource limits."},
    {.key = "limits.memory_fraction", .type = SC_T_REAL, .def = "0.8", .lo_kind = '(',
     .lo = 0, .hi = 1, .hi_kind = ']',
     .doc = "Refuse a plan whose memory estimate exceeds this fraction of the machine's "
            "memory."},
};
const int sc_nparams = (int)(sizeof sc_params / sizeof sc_params[0]);

const sc_param *sc_param_find(const char *key)
{
    for (int i = 0; i < sc_nparams; ++i)
        if (strcmp(sc_params[i].key, key) == 0)
            return &sc_params[i];
    return NULL;
}

/* ---- documentation ------------------------------------------------------------------------- */

/* Every section of a scene, tasks of every type; loaded by the tests, so it stays valid. */
static const char example[] =
    "{\n"
    "  \"title\": \"Poisson problem and operator errors on a 2D jittered lattice\",\n"
    "  \"dim\": 2,\n"
    "  \"cloud\": {\n"
    "    \"source\": \"lattice\",\n"
    "    \"lo\": [0, 0], \"hi\": [1, 1],\n"
    "    \"spacing\": 0.02,\n"
    "    \"jitter\": 0.3,\n"
    "    \"seed\": 7,\n"
    "    \"boundary_layer\": true,\n"
    "    \"h_ratio\": 1.5\n"
    "  },\n"
    "  \"mobility\": { \"type\": \"expression\", \"expression\": [\"1 + x\", \"1 + y\"] },\n"
    "  \"operator\": { \"scheme\": \"qsfdi\", \"kernel\": \"quintic\" },\n"
    "  \"fields\": {\n"
    "    \"u\": \"sin(pi*x)*sin(pi*y)\",\n"
    "    \"v\": \"x^2 + y^2\"\n"
    "  },\n"
    "  \"tasks\": [\n"
    "    { \"type\": \"laplacian\", \"field\": \"v\", \"exact\": \"4\" },\n"
    "    { \"type\": \"divergence\", \"name\": \"flux\", \"field\": \"v\",\n"
    "      \"exact\": \"4 + 4*x + 4*y\", \"norms\": [\"rel_l2\", \"lv78\", \"max_abs\"] },\n"
    "    { \"type\": \"gradient\", \"field\": \"u\",\n"
    "      \"exact\": [\"pi*cos(pi*x)*sin(pi*y)\", \"pi*sin(pi*x)*cos(pi*y)\"],\n"
    "      \"region\": { \"lo\": [0.1, 0.1], \"hi\": [0.9, 0.9] } },\n"
    "    { \"type\": \"hessian\", \"field\": \"v\", \"exact\": [\"2\", \"2\", \"0\"],\n"
    "      \"norms\": [\"max_abs\"], \"region\": \"all\" },\n"
    "    { \"type\": \"interpolate\", \"field\": \"u\", \"exact\": \"sin(pi*x)*sin(pi*y)\",\n"
    "      \"points\": { \"lo\": [0.05, 0.05], \"hi\": [0.95, 0.95], \"spacing\": 0.1 } },\n"
    "    { \"type\": \"solve\", \"name\": \"p\", \"rhs\": \"4 + 4*x + 4*y\",\n"
    "      \"exact\": \"x^2 + y^2\",\n"
    "      \"boundary\": [\n"
    "        { \"where\": \"xlo\", \"type\": \"neumann\", \"value\": \"-2*x\" },\n"
    "        { \"where\": \"all\", \"type\": \"dirichlet\", \"value\": \"x^2 + y^2\" }\n"
    "      ],\n"
    "      \"solver\": \"gmres\", \"precond\": \"jacobi\", \"restart\": 50, \"max_iter\": 2000,\n"
    "      \"rtol\": 1e-10, \"operator\": \"stored\", \"norms\": [\"rel_l2\", \"max_rel\"] },\n"
    "    { \"type\": \"diffuse\", \"name\": \"heat\", \"initial\": \"sin(pi*x)*sin(pi*y)\",\n"
    "      \"boundary_value\": \"0\", \"method\": \"crank_nicolson\", \"t_end\": 0.01,\n"
    "      \"dt\": 0.001, \"pvd\": \"heat.pvd\", \"output_every\": 5 }\n"
    "  ],\n"
    "  \"outputs\": {\n"
    "    \"csv\": \"poisson.csv\",\n"
    "    \"vtu\": \"poisson.vtu\",\n"
    "    \"report\": \"poisson.json\",\n"
    "    \"fields\": [\"u\", \"v\", \"laplacian\", \"flux\", \"p\"]\n"
    "  },\n"
    "  \"limits\": { \"memory_fraction\": 0.5 }\n"
    "}\n";

const char *pst_scene_example(void) { return example; }

/* Hand-written paragraphs of docs/scenes.md, kept here so that the generated file is whole. */
static const char *const intro[] = {
    "A scene is a JSON file that describes a whole run: the particle cloud and its smoothing "
    "length, the mobility, the scheme and kernel, input fields given by expressions, the tasks "
    "(operators, interpolation, solves, time steps), the error norms against exact solutions, "
    "and the outputs. The built-in scene is scenes/default.json.",
    "Every key is declared once in a table (src/app/scene_params.c) from which this page and "
    "`pstencil help scene` are generated. A scene is checked against it before anything runs: "
    "unknown keys, wrong types, out-of-range values, vectors without dim components, missing "
    "required keys and keys that do not apply (rtol on a laplacian task) are errors that name "
    "the key and its line and column, e.g. `scene.json:7:5: key 'cloud.jiter': unknown key "
    "(did you mean 'cloud.jitter'?)`. Columns count characters from 1.",
    "In the key column, `tasks[]` stands for any item of the list and `fields.<name>` for any "
    "name. Overrides are `KEY=VALUE` strings applied to the file before the checks, with list "
    "items numbered from 0: `cloud.jitter=0.3`, `tasks.0.rtol=1e-8`, `fields.v=x*y`, "
    "`cloud.lo=[0,0]`. A value that is valid JSON is taken as JSON, anything else as a string; "
    "an override may create any key of the table, and an error in an override names it.",
    "Expressions are strings in x, y (and z in 3D), docs/expressions.md. Input files "
    "(cloud.file, mobility.file, tasks[].points.file) are relative to the scene file's folder, "
    "outputs to the working directory.",
};

static const char *type_name(const sc_param *p)
{
    switch (p->type) {
    case SC_T_INT: return "int";
    case SC_T_REAL: return "real";
    case SC_T_BOOL: return "bool";
    case SC_T_STRING: return "string";
    case SC_T_ENUM: return "enum";
    case SC_T_EXPR: return "expression";
    case SC_T_EXPRS: return "expression or list";
    case SC_T_VEC: return "vector (dim)";
    case SC_T_PATH: return "path";
    case SC_T_OBJECT: return "object";
    case SC_T_ENUM_OR_OBJECT: return "enum or object";
    case SC_T_AXES: return "bool or list of dim bools";
    case SC_T_LIST: break;
    }
    return p->item == SC_T_OBJECT ? "list of objects"
           : p->item == SC_T_ENUM ? "list of enums"
                                  : "list of strings";
}

/* Print `s`, with '|' escaped in markdown table cells. */
static void put_cell(FILE *f, const char *s, int markdown)
{
    for (; *s; ++s) {
        if (markdown && *s == '|')
            fputc('\\', f);
        fputc(*s, f);
    }
}

/* "a|b" as "`a`, `b`" (markdown) or "a, b". */
static void put_values(FILE *f, const char *values, int markdown)
{
    const char *q = values;
    for (int first = 1; *q; first = 0) {
        size_t n = strcspn(q, "|");
        fprintf(f, "%s%s%.*s%s", first ? "" : ", ", markdown ? "`" : "", (int)n, q,
                markdown ? "`" : "");
        q += n + (q[n] == '|');
    }
}

static void put_allowed(FILE *f, const sc_param *p, int markdown)
{
    if (p->type == SC_T_ENUM && !p->values) {
        for (int i = 0; i < pst_scheme_count(); ++i)
            fprintf(f, "%s%s%s%s", i ? ", " : "", markdown ? "`" : "", pst_scheme_name(i),
                    markdown ? "`" : "");
        return;
    }
    if (p->values) {
        put_values(f, p->values, markdown);
        return;
    }
    if (p->type == SC_T_LIST || p->type == SC_T_OBJECT) {
        if (p->hi_kind)
            fprintf(f, "at most %d %s", (int)p->hi, p->type == SC_T_LIST ? "items" : "entries");
        return;
    }
    if (p->lo_kind && p->hi_kind)
        fprintf(f, "%c%.15g, %.15g%c", p->lo_kind, p->lo, p->hi, p->hi_kind);
    else if (p->lo_kind)
        fprintf(f, "%s %.15g", p->lo_kind == '[' ? ">=" : ">", p->lo);
    else if (p->hi_kind)
        fprintf(f, "%s %.15g", p->hi_kind == ']' ? "<=" : "<", p->hi);
}

static void put_default(FILE *f, const sc_param *p, int markdown)
{
    if (p->flags & SC_F_REQUIRED)
        fputs("required", f);
    else if (p->def)
        fprintf(f, "%s%s%s%s", markdown ? "`" : "", p->def, markdown ? "`" : "",
                p->type == SC_T_VEC ? " (every axis)" : "");
    else
        fputs("none", f);
}

/* The selector that decides whether `p` applies, as "tasks[].type" etc. */
static void put_applies(FILE *f, const sc_param *p, int markdown)
{
    if (!p->applies)
        return;
    const char *dot = strrchr(p->key, '.');
    size_t parent = dot ? (size_t)(dot - p->key) : 0;
    for (int i = 0; i < sc_nparams; ++i) {
        const sc_param *s = &sc_params[i];
        const char *sdot = strrchr(s->key, '.');
        if ((s->flags & SC_F_SELECTOR) && sdot && (size_t)(sdot - s->key) == parent &&
            strncmp(s->key, p->key, parent) == 0) {
            fprintf(f, "%s%s%s = ", markdown ? "`" : "", s->key, markdown ? "`" : "");
            put_values(f, p->applies, markdown);
            return;
        }
    }
}

/* Words of `s` wrapped at 92 columns, each line indented by `indent` spaces. */
static void put_wrapped(FILE *f, const char *s, int indent)
{
    int col = 0;
    while (*s) {
        size_t n = strcspn(s, " ");
        if (col > indent && col + 1 + (int)n > 92) {
            fputc('\n', f);
            col = 0;
        }
        if (col == 0)
            col = fprintf(f, "%*s", indent, "");
        else
            col += fprintf(f, " ");
        col += fprintf(f, "%.*s", (int)n, s);
        s += n;
        s += strspn(s, " ");
    }
    fputc('\n', f);
}

static void print_markdown(FILE *f)
{
    fputs("# Scene files\n\n"
          "<!-- Generated by `pstencil help scene --markdown` from src/app/scene_params.c; "
          "test_scene checks that this file matches. Edit the table, not this file. -->\n\n",
          f);
    for (size_t k = 0; k < sizeof intro / sizeof intro[0]; ++k) {
        put_wrapped(f, intro[k], 0);
        fputc('\n', f);
    }
    fputs("## Keys\n\n"
          "| key | type | default | units | allowed | applies when | description |\n"
          "|---|---|---|---|---|---|---|\n",
          f);
    for (int i = 0; i < sc_nparams; ++i) {
        const sc_param *p = &sc_params[i];
        fprintf(f, "| `%s` | %s | ", p->key, type_name(p));
        put_default(f, p, 1);
        fprintf(f, " | %s | ", p->units ? p->units : "");
        put_allowed(f, p, 1);
        fputs(" | ", f);
        put_applies(f, p, 1);
        fputs(" | ", f);
        put_cell(f, p->doc, 1);
        fputs(" |\n", f);
    }
    fputs("\n## Example\n\n"
          "Every section of a scene and a task of every type:\n\n```json\n",
          f);
    fputs(example, f);
    fputs("```\n\n"
          "- The cloud is a 51 x 51 lattice jittered by 0.3 s0 inside an unjittered Dirichlet "
          "layer, h = 1.5 s0.\n"
          "- The mobility is the diagonal tensor diag(1 + x, 1 + y); it enters the divergence "
          "task and the solve, not the laplacian task.\n"
          "- Tasks without a name are named after their type: `laplacian`, `gradient`, "
          "`hessian`, `interpolate`.\n"
          "- The laplacian task gives no norms, so it gets rel_l2 and max_abs; the gradient "
          "task measures its errors only inside [0.1, 0.9]^2.\n"
          "- The solve makes the particles of the x = 0 side Neumann (du/dn = -2x, which is 0 "
          "there) and every other boundary particle Dirichlet: the first matching group "
          "wins.\n"
          "- The diffuse task steps du/dt = div(M grad u) from sin(pi x) sin(pi y) with u = 0 "
          "held at the boundary: ten Crank-Nicolson steps of 0.001, each one GMRES solve with "
          "the same solver handle, and writes heat.pvd with heat_000000.vtu, heat_000005.vtu "
          "and heat_000010.vtu (docs/time-stepping.md).\n"
          "- outputs.fields picks the columns of poisson.csv and poisson.vtu; poisson.json "
          "holds the timings, the solver's result and the norms.\n",
          f);
}

static void print_text(FILE *f)
{
    fputs("Scene files (docs/scenes.md)\n\n", f);
    for (size_t k = 0; k < sizeof intro / sizeof intro[0]; ++k) {
        put_wrapped(f, intro[k], 0);
        fputc('\n', f);
    }
    fputs("Keys:\n\n", f);
    for (int i = 0; i < sc_nparams; ++i) {
        const sc_param *p = &sc_params[i];
        fprintf(f, "%s\n    %s, default ", p->key, type_name(p));
        put_default(f, p, 0);
        if (p->units)
            fprintf(f, ", units %s", p->units);
        if (p->values || p->lo_kind || p->hi_kind || p->type == SC_T_ENUM) {
            fputs(", allowed: ", f);
            put_allowed(f, p, 0);
        }
        if (p->applies) {
            fputs(", only when ", f);
            put_applies(f, p, 0);
        }
        fputc('\n', f);
        put_wrapped(f, p->doc, 4);
    }
    fputs("\n'pstencil help scene --markdown' prints this as docs/scenes.md, with an example.\n",
          f);
}

void pst_scene_print_help(FILE *f, int markdown)
{
    if (markdown)
        print_markdown(f);
    else
        print_text(f);
}
