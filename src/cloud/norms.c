/* Error norms of the papers (docs/norms.md): the QSFDI paper's eqs. 11, 14/15 and the
 * Lukyanov-Vuik paper's eqs. 78 and 95, plus maxima. One serial pass in particle order, so
 * the value is the same for every thread count; O(n) beside the operators' O(n * neighbours). */
#include "cloud_layout.h"
#include "check.h"

#include <math.h>
#include <string.h>

static const char *const norm_names[PST_NNORMS] = {
    "rel_l2", "qsfdi11", "qsfdi11_normalised", "lv78", "lv95", "max_abs", "max_rel"};

const char *pst_norm_name(int norm)
{
    return norm >= 0 && norm < PST_NNORMS ? norm_names[norm] : NULL;
}

pst_norm pst_norm_from_name(const char *name)
{
    for (int k = 0; k < PST_NNORMS; ++k)
        if (strcmp(name, norm_names[k]) == 0)
            return (pst_norm)k;
    return PST_NORM_UNKNOWN;
}

/* Euclidean length over the components of particle i. */
static double length(int ncomp, const double *const *v, size_t i)
{
    double s = 0;
    for (int a = 0; a < ncomp; ++a)
        s += v[a][i] * v[a][i];
    return sqrt(s);
}

/* The norms over n values with volumes V (NULL: 1 each); `id` (NULL: the index) names a
 * particle in messages. */
static int error_norm(size_t n, const double *Vs, const int64_t *id, int ncomp,
                      const double *const *approx, const double *const *exact,
                      const uint8_t *mask, int norm, double *out, char *err)
{
    *out = 0;
    PST_CHECK(norm < 0 || norm >= PST_NNORMS || ncomp < 1 || ncomp > 6, PST_EINVAL, err,
              "error norm: unknown norm %d or bad component count %d", norm, ncomp);
    const int pointwise_relative = norm == PST_NORM_QSFDI11 ||
                                   norm == PST_NORM_QSFDI11_NORMALISED || norm == PST_NORM_LV95;
    const char *where = id ? "particle (input order)" : "point"; /* for the messages */
    double num = 0, den = 0, vol = 0, emax = 0, xmax = 0;
    size_t used = 0;
    for (size_t i = 0; i < n; ++i) {
        if (mask && !mask[i])
            continue;
        double e2 = 0;
        for (int a = 0; a < ncomp; ++a)
            e2 += (approx[a][i] - exact[a][i]) * (approx[a][i] - exact[a][i]);
        double ex = length(ncomp, exact, i), e = sqrt(e2);
        long long at = id ? (long long)id[i] : (long long)i;
        PST_CHECK(!isfinite(e), PST_ENUMERIC, err,
                  "error norm %s: the value at %s %lld is not finite", norm_names[norm], where, at);
        PST_CHECK(pointwise_relative && ex == 0, PST_ENUMERIC, err,
                  "error norm %s is relative to the exact value, which is 0 at %s %lld: use "
                  "rel_l2, lv78 or max_abs",
                  norm_names[norm], where, at);
        double V = Vs ? Vs[i] : 1.0;
        ++used;
        vol += V;
        emax = e > emax ? e : emax;
        xmax = ex > xmax ? ex : xmax;
        switch (norm) {
        case PST_NORM_REL_L2: num += e2; den += ex * ex; break;
        case PST_NORM_LV78: num += V * e2; break;
        default: num += V * e2 / (ex * ex); break; /* the pointwise-relative norms */
        }
    }
    PST_CHECK(used == 0, PST_EINVAL, err, "error norm %s: the region holds no particle",
              norm_names[norm]);
    switch (norm) {
    case PST_NORM_REL_L2:
    case PST_NORM_MAX_REL:
        den = norm == PST_NORM_REL_L2 ? den : xmax;
        PST_CHECK(den == 0, PST_ENUMERIC, err,
                  "error norm %s: the exact values are all 0 in the region", norm_names[norm]);
        *out = norm == PST_NORM_REL_L2 ? sqrt(num / den) : emax / den;
        break;
    case PST_NORM_QSFDI11: *out = sqrt(num); break;
    case PST_NORM_MAX_ABS: *out = emax; break;
    default: *out = sqrt(num / vol); break; /* qsfdi11_normalised, lv78, lv95 */
    }
    return PST_OK;
}

int pst_error_norm(const pst_cloud *c, int ncomp, const double *const *approx,
                   const double *const *exact, const uint8_t *mask, int norm, double *out,
                   char *err)
{
    return error_norm(c->n, c->V, c->id, ncomp, approx, exact, mask, norm, out, err);
}

int pst_error_norm_points(size_t n, int ncomp, const double *const *approx,
                          const double *const *exact, int norm, double *out, char *err)
{
    return error_norm(n, NULL, NULL, ncomp, approx, exact, NULL, norm, out, err);
}
