/* The spectrum of a scene's operator (`pstencil analyse`, docs/stability.md): the eigenvalues
 * of the block of L on the unknowns (interior and Neumann rows and columns). -L should be
 * positive stable: an eigenvalue with real part >= 0 has the wrong sign. */
#ifndef PSTENCIL_ANALYSE_H
#define PSTENCIL_ANALYSE_H

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

/* Build the scene's operator, assemble L, and compute every eigenvalue of its unknowns' block
 * with LAPACKE_dgeev. More than max_unknowns unknowns: PST_EINPUT. Errors with the reason in
 * err (PST_ENUMERIC when dgeev fails). */
int pst_analyse_scene(const pst_scene *s, int quiet, size_t max_unknowns, pst_spectrum *sp,
                      char *err, size_t errlen);
void pst_spectrum_free(pst_spectrum *sp);

/* DIR/spectrum.csv (re,im), all or nothing. */
int pst_spectrum_write_csv(const pst_spectrum *sp, const char *path, char *err, size_t errlen);
/* DIR/spectrum.png: a gnuplot scatter, wrong-sign eigenvalues highlighted; written to a
 * temporary name and renamed. PST_EIO (gnuplot missing or failing) with the reason in err. */
int pst_spectrum_plot(const pst_spectrum *sp, const char *path, const char *title, char *err,
                      size_t errlen);

#endif
