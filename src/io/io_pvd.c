/* VTK Collection files (.pvd): ParaView opens one as a series of datasets, stepping through
 * the timesteps and showing the parts of one timestep together (docs/io.md). */
#include "check.h"

#include "pstencil/io.h"

#include <math.h>
#include <stdio.h>

typedef struct {
    const pst_pvd_dataset *d;
    size_t n;
} pvd_job;

/* An XML attribute value: the five characters XML reserves written as entities. */
static void put_escaped(FILE *f, const char *s)
{
    for (; *s; ++s) {
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&apos;", f); break;
        default: fputc(*s, f); break;
        }
    }
}

static void write_pvd(FILE *f, const void *job)
{
    const pvd_job *j = job;
    fputs("<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
          "  <Collection>\n",
          f);
    for (size_t k = 0; k < j->n; ++k) {
        fprintf(f, "    <DataSet timestep=\"%.17g\" part=\"%d\" file=\"", j->d[k].timestep,
                j->d[k].part);
        put_escaped(f, j->d[k].file);
        fputs("\"/>\n", f);
    }
    fputs("  </Collection>\n"
          "</VTKFile>\n",
          f);
}

int pst_write_pvd(const char *path, const pst_pvd_dataset *d, size_t n, char *err)
{
    for (size_t k = 0; k < n; ++k) {
        PST_CHECK(!d[k].file || !d[k].file[0], PST_EINVAL, err,
                  "%s: dataset %zu has no file name", path, k);
        PST_CHECK(!isfinite(d[k].timestep), PST_EINVAL, err,
                  "%s: dataset %zu (%s): timestep is not finite", path, k, d[k].file);
        PST_CHECK(d[k].part < 0, PST_EINVAL, err, "%s: dataset %zu (%s): part %d is negative",
                  path, k, d[k].file, d[k].part);
    }
    pvd_job job = {d, n};
    return pst_write_atomic(path, write_pvd, &job, err);
}
