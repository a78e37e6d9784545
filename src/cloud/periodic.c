/* Periodic boxes: the axes a cloud wraps around, the check that positions lie in the box, and
 * the fold of moved particles back into it (docs/periodic.md). */
#include "check.h"
#include "cloud_layout.h"

#include <math.h>

int pst_cloud_set_periodic(pst_cloud *c, const int periodic[3], const double lo[3],
                           const double hi[3], char *err)
{
    for (int d = 0; d < c->dim; ++d)
        PST_CHECK(periodic[d] && !(isfinite(lo[d]) && isfinite(hi[d]) && lo[d] < hi[d] &&
                                   isfinite(hi[d] - lo[d])),
                  PST_EINVAL, err,
                  "periodic box: along %c it must be finite with lo < hi (got [%g, %g])",
                  "xyz"[d], lo[d], hi[d]);
    for (int d = 0; d < 3; ++d) {
        int per = d < c->dim && periodic[d];
        c->periodic[d] = (uint8_t)per;
        c->box_lo[d] = per ? lo[d] : 0.0;
        c->box_hi[d] = per ? hi[d] : 0.0;
    }
    return PST_OK;
}

int pst_cloud_periodic(const pst_cloud *c, int periodic[3], double lo[3], double hi[3])
{
    int count = 0;
    for (int d = 0; d < 3; ++d) {
        if (periodic)
            periodic[d] = c->periodic[d];
        if (lo)
            lo[d] = c->box_lo[d];
        if (hi)
            hi[d] = c->box_hi[d];
        count += c->periodic[d];
    }
    return count;
}

void pst_cloud_wrap(pst_cloud *c)
{
    for (int d = 0; d < c->dim; ++d) {
        if (!c->periodic[d])
            continue;
        double lo = c->box_lo[d], hi = c->box_hi[d], P = hi - lo;
        double *x = c->x[d];
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < c->n; ++i) {
            if (!isfinite(x[i]) || (x[i] >= lo && x[i] < hi))
                continue;
            double t = x[i] - lo;
            t -= P * floor(t / P);
            double w = lo + t;
            x[i] = w >= hi || w < lo ? lo : w;
        }
    }
}

int pst_cloud_check_box(const pst_cloud *c, char *err)
{
    for (int d = 0; d < c->dim; ++d) {
        if (!c->periodic[d])
            continue;
        for (size_t i = 0; i < c->n; ++i)
            PST_CHECK(!(c->x[d][i] >= c->box_lo[d] && c->x[d][i] < c->box_hi[d]), PST_EINPUT,
                      err,
                      "particle %lld: %c = %.17g lies outside the periodic box [%.17g, %.17g) "
                      "(pst_cloud_wrap folds moved particles back)",
                      (long long)c->id[i], "xyz"[d], c->x[d][i], c->box_lo[d], c->box_hi[d]);
    }
    return PST_OK;
}
