/* The minimum image of a pair offset in a periodic box (docs/periodic.md), shared by the
 * neighbour search, the kernels and their lanes. Internal. */
#ifndef PSTENCIL_MIN_IMAGE_H
#define PSTENCIL_MIN_IMAGE_H

/* The minimum image of an offset d along an axis of period P (half period hP): d - P above
 * hP, d + P below -hP, d itself otherwise and on an axis that is not periodic (P = 0,
 * hP = infinity: d - 0 * 0 is d bit for bit, -0 included). Branch-free, so the loops that
 * call it stay vector loops. With positions inside the box |d| < P, so one period is enough. */
static inline double pst_min_image(double d, double P, double hP)
{
    return d - P * (double)((d > hP) - (d < -hP));
}

#endif
