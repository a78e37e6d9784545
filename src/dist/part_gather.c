/* The owned values of every rank's part gathered into a whole-cloud array on every rank
 * (MPI_Allgatherv over MPI_COMM_WORLD): how a distributed solve's answer reaches the outputs,
 * which are written in the cloud's order. */
#include "check.h"
#include "pstencil/dist.h"

#include <mpi.h>
#include <stdlib.h>

int pst_part_gather(const pst_part *p, const double *local, double *whole, char *err)
{
    PST_CHECK(!p || !local || !whole, PST_EINVAL, err, "part gather: NULL argument");
    pst_part_info pi;
    pst_part_layout(p, &pi);
    int up = 0, size = 1;
    MPI_Initialized(&up);
    if (up)
        MPI_Comm_size(MPI_COMM_WORLD, &size);
    PST_CHECK(!up || size != pi.ranks, PST_EINVAL, err,
              "part gather: the part is one of %d ranks, MPI runs %d", pi.ranks, up ? size : 0);
    PST_CHECK(pi.n > (size_t)INT32_MAX, PST_EINVAL, err,
              "part gather: %zu particles exceed MPI's int counts", pi.n);
    int *count = malloc(2 * (size_t)pi.ranks * sizeof *count);
    PST_CHECK_ALLOC(count, err, "part gather: out of memory");
    int *first = count + pi.ranks;
    for (int q = 0; q < pi.ranks; ++q) { /* the ranges of pst_part_create */
        size_t lo = pi.n * (size_t)q / (size_t)pi.ranks;
        size_t hi = pi.n * (size_t)(q + 1) / (size_t)pi.ranks;
        first[q] = (int)lo;
        count[q] = (int)(hi - lo);
    }
    int rc = MPI_Allgatherv(local + pi.own0, count[pi.rank], MPI_DOUBLE, whole, count, first,
                            MPI_DOUBLE, MPI_COMM_WORLD);
    free(count);
    PST_CHECK(rc != MPI_SUCCESS, PST_EINVAL, err, "part gather: MPI_Allgatherv failed (%d)", rc);
    return PST_OK;
}
