/* What the distributed layer gives with or without PETSc: this process's place among the ranks
 * of MPI_COMM_WORLD (the front end does not include MPI itself) and the solve defaults. */
#include "pstencil/dist.h"

#include <mpi.h>

void pst_mpi_rank(int *rank, int *ranks)
{
    int started = 0, finished = 0;
    *rank = 0;
    *ranks = 1;
    MPI_Initialized(&started);
    MPI_Finalized(&finished);
    if (!started || finished)
        return;
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, ranks);
}

void pst_petsc_defaults(pst_petsc_opts *o)
{
    *o = (pst_petsc_opts){.rtol = 1e-8, .max_iter = 1000, .restart = 30,
                          .amg_source = PST_AMG_AUTO, .amg_radius = -1};
}
