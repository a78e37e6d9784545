/* The gnuplot plumbing shared by the plots (pstencil plot; analyse's spectrum.png and
 * vonneumann.png): a pipe to gnuplot writing a PNG to a temporary name, checked and renamed
 * over the target, so a failed plot never leaves a half-written file. */
#ifndef PSTENCIL_GNUPLOT_H
#define PSTENCIL_GNUPLOT_H

#include <stddef.h>
#include <stdio.h>

typedef struct {
    FILE *g;             /* the pipe: write plot commands and inline data here          */
    char tmp[4400];      /* the temporary PNG                                            */
    const char *path;    /* the target PNG                                               */
} pst_gnuplot;

/* Start gnuplot with a 900 x 700 PNG terminal (pngcairo when available), the output set to a
 * temporary name beside `path`, and `title` (not enhanced). PST_EIO with the reason in err when
 * gnuplot cannot be started. */
int pst_gnuplot_begin(pst_gnuplot *gp, const char *path, const char *title, char *err,
                      size_t errlen);

/* Write s as a gnuplot single-quoted string (a quote is doubled). */
void pst_gnuplot_quoted(FILE *g, const char *s);

/* 1 when the file at path starts with the PNG signature. */
int pst_file_is_png(const char *path);

/* Close the pipe, check the PNG signature and rename the temporary file to the target.
 * PST_EIO (gnuplot failed, no PNG, rename failed) with the reason in err; the temporary file
 * is removed on every failure. */
int pst_gnuplot_end(pst_gnuplot *gp, char *err, size_t errlen);

#endif
