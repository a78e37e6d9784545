/*
 * pstencil — meshless discretisations of the Laplacian and of div(M grad u) on disordered
 * particle clouds in 2D and 3D. This header includes the whole public API, one header per
 * area under pstencil/ (core, cloud, io, kernel, neighbours, operator, solve, norms, spe10).
 *
 * Conventions of the whole API:
 *   - opaque handles with create/destroy pairs;
 *   - every fallible call returns an int: PST_OK (0) or a negative PST_E* code, and
 *     pst_strerror() names the code;
 *   - one way to get the detail message: a call that can fail for more than one reason takes
 *     `char *err` (PST_ERRLEN bytes, or NULL for none) as its last argument and writes the
 *     reason there on failure; a solve's outcome (converged or not, and why) is in its result;
 *   - the library never prints, never calls exit(), keeps no global mutable state;
 *   - threads are OpenMP threads: results are identical for every thread count.
 *   - the library leaves the OpenMP wait policy to its host: on shared cores a host should
 *     start with OMP_WAIT_POLICY=PASSIVE in its environment (libgomp reads it when it is
 *     loaded, so setenv in main is too late; the pstencil program re-executes itself with it
 *     set, docs/cli.md, "Threads on shared cores").
 */
#ifndef PSTENCIL_H
#define PSTENCIL_H

#include "pstencil/core.h"
#include "pstencil/cloud.h"
#include "pstencil/io.h"
#include "pstencil/kernel.h"
#include "pstencil/neighbours.h"
#include "pstencil/operator.h"
#include "pstencil/solve.h"
#include "pstencil/dist.h"
#include "pstencil/norms.h"
#include "pstencil/normals.h"
#include "pstencil/spe10.h"

#endif /* PSTENCIL_H */
