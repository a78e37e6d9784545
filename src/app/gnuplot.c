/* A PNG from gnuplot through a pipe, written to a temporary name and renamed. */
#define _POSIX_C_SOURCE 200809L /* popen, pclose, getpid */
#include "gnuplot.h"

#include "pstencil.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

void pst_gnuplot_quoted(FILE *g, const char *s)
{
    fputc('\'', g);
    for (; *s; ++s) {
        if (*s == '\'')
            fputc('\'', g);
        fputc(*s, g);
    }
    fputc('\'', g);
}

int pst_file_is_png(const char *path)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char buf[8];
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    size_t got = fread(buf, 1, 8, f);
    fclose(f);
    return got == 8 && memcmp(buf, sig, 8) == 0;
}

int pst_gnuplot_begin(pst_gnuplot *gp, const char *path, const char *title, char *err,
                      size_t errlen)
{
    gp->path = path;
    snprintf(gp->tmp, sizeof gp->tmp, "%s.%ld.tmp", path, (long)getpid());
    /* gnuplot's messages go to our stderr; the plot goes to the temporary file */
    gp->g = popen("exec gnuplot", "w");
    if (!gp->g) {
        snprintf(err, errlen, "cannot start gnuplot (install gnuplot-nox)");
        return PST_EIO;
    }
    fprintf(gp->g, "set encoding utf8\n"
                   "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
                   "  set terminal pngcairo enhanced size 900,700 font ',10'\n"
                   "} else {\n"
                   "  set terminal png enhanced size 900,700\n"
                   "}\n"
                   "set output ");
    pst_gnuplot_quoted(gp->g, gp->tmp);
    fprintf(gp->g, "\nset title ");
    pst_gnuplot_quoted(gp->g, title);
    fprintf(gp->g, " noenhanced\n");
    return PST_OK;
}

int pst_gnuplot_end(pst_gnuplot *gp, char *err, size_t errlen)
{
    fprintf(gp->g, "unset output\nexit\n");
    int status = pclose(gp->g);
    gp->g = NULL;
    if (status != 0 || !pst_file_is_png(gp->tmp)) {
        remove(gp->tmp);
        snprintf(err, errlen, "gnuplot failed (no PNG written)");
        return PST_EIO;
    }
    if (rename(gp->tmp, gp->path) != 0) {
        remove(gp->tmp);
        snprintf(err, errlen, "cannot rename %s to %s", gp->tmp, gp->path);
        return PST_EIO;
    }
    return PST_OK;
}
