/* `pstencil analyse` (docs/stability.md): the stability of a scene's operator.
 *   - the spectrum: the eigenvalues of the block of L on the unknowns (interior and Neumann
 *     rows and columns). -L should be positive stable: an eigenvalue with real part >= 0 has
 *     the wrong sign;
 *   - von Neumann growth factors (analyse_vonneumann.h);
 *   - the monotonicity audit of K = -L (pst_op_audit_rows) and its non-positive diagonals;
 *   - the discrete maximum principle (analyse_dmp.h).
 * The parts take an operator (or its assembled matrix), so tests can call them on any cloud;
 * pst_analyse_scene_all runs them all on a scene. */
#ifndef PSTENCIL_ANALYSE_H
#define PSTENCIL_ANALYSE_H

#include "analyse_dmp.h"
#include "analyse_vonneumann.h"
#include "scene.h"

#include <stddef.h>

enum { PST_ANALYSE_MAX_UNKNOWNS = 5000 };

typedef struct {
    size_t n;            /* unknowns = eigenvalues                                     */
    size_t particles;
    double *re, *im;     /* n eigenvalues, sorted by real part (then imaginary part)   */
    double radius;       /* max |lambda|                                               */
    double min_abs;      /* min |lambda|                                               */
    size_t wrong_sign;   /* eigenvalues with re >= 0                                   */
    double max_re;       /* the largest real part (positive: wrong sign)               */
} pst_spectrum;

/* Free a spectrum's arrays and zero its count (a zeroed spectrum is fine). */
void pst_spectrum_free(pst_spectrum *sp);

/* The spectrum of an assembled operator a of cloud c (cloud order): every eigenvalue of the
 * unknowns' block, LAPACKE_dgeev. PST_EINPUT when there are no unknowns, PST_ENUMERIC when
 * dgeev fails, PST_ENOMEM; the reason in err (prefixed with `name`). */
int pst_spectrum_compute(const pst_cloud *c, const pst_csr *a, const char *name,
                         pst_spectrum *sp, char *err, size_t errlen);

typedef struct {
    double tau;          /* von Neumann time-step factor: dt = tau s0^2 (default 0.25)       */
    int waves;           /* N of the wave-vector set (default 4)                               */
} pst_analyse_opts;
/* tau 0.25 (the paper's), N = 4. */
void pst_analyse_defaults(pst_analyse_opts *o);

/* Everything `pstencil analyse` reports. */
typedef struct {
    pst_spectrum spectrum;
    pst_vonneumann vn;
    int s0_from_spacing;     /* 1: s0 is cloud.spacing; 0: the cloud's mean nearest-neighbour
                                distance (a cloud read from a file has no spacing)            */
    pst_op_audit audit;
    size_t diag_rows;        /* unknown rows (interior and Neumann)                            */
    size_t nonpositive_diag; /* ... where K = -L has a diagonal <= 0                           */
    pst_dmp dmp;
    pst_op_opts opts;        /* the operator's parameters, as built (pst_op_options)          */
    pst_cloud *cloud;        /* the analysed cloud with the per-particle findings as fields:
                                audit_positive_offdiag, audit_not_dominant, audit_lemma3_mixed,
                                audit_xi_large (0/1, pst_op_audit_flags) and vn_max_abs (the
                                largest |lambda| over the wave vectors)                        */
    uint8_t *status;         /* the operator's row status, cloud order                         */
} pst_analysis;

/* Build the scene's operator once and run every part on it (spectrum, von Neumann with o,
 * audit, maximum principle). More than max_unknowns unknowns: PST_EINPUT; PST_ENUMERIC when
 * dgeev fails; an invalid o is PST_EINVAL; the reason in err. an is zeroed first and is safe to free after any failure. */
int pst_analyse_scene_all(const pst_scene *s, const pst_analyse_opts *o, int quiet,
                          size_t max_unknowns, pst_analysis *an, char *err, size_t errlen);
/* Free what an analysis holds (a zeroed or failed one is fine). */
void pst_analysis_free(pst_analysis *an);

/* DIR/analysis.vtu: the analysed cloud with its row status and per-particle findings (the
 * fields of an->cloud), for ParaView: where the degenerate, non-monotone and growing rows
 * are. All or nothing (pst_cloud_write_vtu). */
int pst_analysis_write_vtu(const pst_analysis *an, const char *path, char *err, size_t errlen);

/* DIR/analysis.json: every number of an, with the scene's path, tau and N (cJSON; all or
 * nothing). No value is NaN or infinite (an infinity would be written as null, so absent
 * numbers are omitted). */
int pst_analysis_write_json(const pst_analysis *an, const char *scene_path, const char *path,
                            char *err, size_t errlen);

/* DIR/spectrum.csv (re,im), all or nothing. */
int pst_spectrum_write_csv(const pst_spectrum *sp, const char *path, char *err, size_t errlen);
/* DIR/spectrum.png: a gnuplot scatter, wrong-sign eigenvalues highlighted; written to a
 * temporary name and renamed. PST_EIO (gnuplot missing or failing) with the reason in err. */
int pst_spectrum_plot(const pst_spectrum *sp, const char *path, const char *title, char *err,
                      size_t errlen);

#endif
