/* QSFDI's interpolation at points (eqs. 32-35), from the fit of qsfdi_fit.h: the value and the
 * Laplacian at arbitrary points, each from the particles around it. */
#include "qsfdi_fit.h"

#include <math.h>

/* Value and Laplacian at point p with neighbours idx[e0..e1) and smoothing length h:
 * Phi_k = omega1_k - tau^T Phi^all_k, <p> = sum Phi_k u_k / M0, lap = sum a_k (u_k - <p>).
 * Returns 0 (fallback) for too few neighbours, a singular fit or M0 not positive. The data
 * are taken relative to uref (the nearest neighbour's value) to keep rounding small. */
PST_KHOT int qs_point_t(const qs_ctx *k, int D, const double p[3], double h, const uint32_t *idx,
                      int64_t e0, int64_t e1, const double *u, double uref, double *value,
                      double *lap)
{
    const int n2 = QS_N2(D), nq = QS_NQ(D);
    double mom[QS_NMOM], ih = 1.0 / h;
    if (qs_moments(k, D, p, ih, idx, e0, e1, mom, mom + n2) < qs_min(D))
        return 0;
    qs_state st;
    if (qs_invert(k, D, mom, mom + n2, &st) >= PST_ROW_RANK_DEFICIENT)
        return 0;
    /* tau = sum omega1 (r; r2s / 2; r2c), omega1 = w / d */
    double tau[9] = {0};
    for (int64_t e = e0; e < e1; ++e) {
        double r[3] = {0, 0, 0}, o2, id2, qm[6];
        qs_pair(k, D, p, ih, idx[e], r, &o2, &id2);
        qs_quad(D, r, qm);
        double o1 = o2 * sqrt(qm[0] + qm[1] + (D == 3 ? qm[2] : 0.0)); /* w/d = omega2 d */
        for (int a = 0; a < D; ++a)
            tau[a] += o1 * r[a];
        for (int a = 0; a < nq; ++a)
            tau[D + a] += o1 * (a < D ? 0.5 : 1.0) * qm[a];
    }
    double kt[15], kl[15], one[3] = {1, 1, 1}, zero[3] = {0, 0, 0};
    qs_functional(D, &st, tau, tau + D, tau + 2 * D, kt);
    qs_functional(D, &st, zero, one, zero, kl);
    double sp = 0, m0 = 0, sphi = 0, sa = 0, sau = 0;
    for (int64_t e = e0; e < e1; ++e) {
        double r[3] = {0, 0, 0}, o2, id2;
        size_t j = idx[e];
        qs_pair(k, D, p, ih, j, r, &o2, &id2);
        double d2 = 0;
        for (int a = 0; a < D; ++a)
            d2 += r[a] * r[a];
        double o1 = o2 * sqrt(d2);
        double phi = o1 - qs_weight(D, r, o2, id2, kt), a = qs_weight(D, r, o2, id2, kl);
        double du = u[j] - uref;
        sp += phi * du;
        m0 += phi;
        sphi += fabs(phi);
        sa += a;
        sau += a * du;
    }
    if (!(fabs(m0) > k->rank_tol * sphi))
        return 0; /* M0 = 0: the value is undetermined (e.g. neighbours on one circle) */
    double v = sp / m0;
    *value = uref + v;
    *lap = (sau - sa * v) * ih * ih;
    return 1;
}

int pst_qsfdi_interpolate(const pst_op *op, const double *const pts[3], size_t m,
                          const double *u, double *value, double *lap, size_t *fallbacks,
                          char *err)
{
    qs_ctx k = make_ctx(op);
    int D = op->dim;
    double h = pst_cloud_h_max(op->cloud);
    int64_t *off;
    uint32_t *idx;
    int st = pst_points_neighbours(op->cloud, pts, m, k.supp * h, &off, &idx, err);
    if (st != PST_OK)
        return st;
    size_t nfb = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : nfb)
    for (size_t b = 0; b < pst_chunks(m, PST_CHUNK); ++b)
        PST_CHUNK_ROWS(op->tally, b, m, PST_CHUNK, q) {
            double p[3] = {0, 0, 0}, v = 0, l = 0;
            for (int a = 0; a < D; ++a)
                p[a] = pts[a][q];
            /* the nearest particle: among the neighbours, else over the whole cloud (rare) */
            size_t near = 0;
            double best = INFINITY;
            int64_t e0 = off[q], e1 = off[q + 1];
            size_t cand = e0 < e1 ? (size_t)(e1 - e0) : op->n;
            for (size_t t = 0; t < cand; ++t) {
                size_t j = e0 < e1 ? idx[e0 + (int64_t)t] : t;
                double d2 = 0;
                for (int a = 0; a < D; ++a) {
                    double t = pst_offset(&k.c, a, k.c.x[a][j], p[a]);
                    d2 += t * t;
                }
                if (d2 < best) {
                    best = d2;
                    near = j;
                }
            }
            double uref = op->n ? u[near] : 0.0;
            int ok = D == 2 ? qs_point_t(&k, 2, p, h, idx, e0, e1, u, uref, &v, &l)
                            : qs_point_t(&k, 3, p, h, idx, e0, e1, u, uref, &v, &l);
            if (!ok) {
                v = uref;
                l = 0;
                ++nfb;
            }
            if (value)
                value[q] = v;
            if (lap)
                lap[q] = l;
        }
    pst_free(off);
    pst_free(idx);
    *fallbacks = nfb;
    return PST_OK;
}
