/* Writing clouds as VTK XML UnstructuredGrid files (.vtu) for ParaView (layout: docs/io.md).
 * One table of array descriptors drives both halves of the file: the XML header, which needs
 * every array's offset into the appended block before any data is written, and the appended
 * block itself (per array a UInt64 byte count, then the values). Values are stored byte by
 * byte in little-endian order, so the file is the same on any host; rows are emitted in input
 * order (by ids) through small gather buffers, and the file goes through pst_write_atomic. */
#include "cloud_layout.h"
#include "check.h"

#include <stdlib.h>
#include <string.h>

enum { VTU_F64, VTU_I64, VTU_U8 };

/* Where an array's values come from. */
enum {
    SRC_DOUBLES,     /* Float64, 1 or 3 components: src[k], or fill[k] where src[k] is NULL */
    SRC_IDS,         /* Int64: the ids                                                       */
    SRC_CONNECTIVITY,/* Int64: row r (cell r holds point r)                                  */
    SRC_OFFSETS,     /* Int64: r + 1 (end of cell r in the connectivity)                     */
    SRC_BYTES,       /* UInt8: bytes[i]                                                      */
    SRC_VERTEX       /* UInt8: 1 (VTK_VERTEX) for every cell                                 */
};

typedef struct {
    const char *name;
    int type, ncomp, src;
    const double *data[3];
    double fill[3];
    const uint8_t *bytes;
    uint64_t offset;   /* into the appended block, from the byte after '_' */
} vtu_array;

enum { SEC_POINTDATA, SEC_POINTS, SEC_CELLS, SEC_END };

typedef struct {
    const pst_cloud *c;
    const size_t *inv;       /* inv[r] = particle of input row r */
    vtu_array *a;
    size_t na, sec_start[SEC_END + 1];
} vtu_job;

static const char *const type_names[] = {"Float64", "Int64", "UInt8"};
static const size_t type_sizes[] = {8, 8, 1};

static uint64_t array_bytes(const vtu_array *a, size_t n)
{
    return (uint64_t)n * (uint64_t)a->ncomp * type_sizes[a->type];
}

static void store_le64(unsigned char *p, uint64_t v)
{
    for (int b = 0; b < 8; ++b)
        p[b] = (unsigned char)(v >> (8 * b));
}

static void store_f64(unsigned char *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    store_le64(p, u);
}

/* ---- the appended block ------------------------------------------------------------------ */

#define VTU_CHUNK 1024 /* rows per gather buffer */

static void put_array(FILE *f, const vtu_job *w, const vtu_array *a)
{
    const pst_cloud *c = w->c;
    size_t n = c->n, width = (size_t)a->ncomp * type_sizes[a->type];
    unsigned char buf[VTU_CHUNK * 3 * 8];
    store_le64(buf, array_bytes(a, n));
    fwrite(buf, 1, 8, f);
    for (size_t r0 = 0; r0 < n && !ferror(f); r0 += VTU_CHUNK) {
        size_t rows = n - r0 < VTU_CHUNK ? n - r0 : VTU_CHUNK;
        for (size_t k = 0; k < rows; ++k) {
            size_t r = r0 + k, i = w->inv[r];
            unsigned char *p = buf + k * width;
            switch (a->src) {
            case SRC_DOUBLES:
                for (int m = 0; m < a->ncomp; ++m)
                    store_f64(p + 8 * m, a->data[m] ? a->data[m][i] : a->fill[m]);
                break;
            case SRC_IDS:
                store_le64(p, (uint64_t)c->id[i]);
                break;
            case SRC_CONNECTIVITY:
                store_le64(p, (uint64_t)r);
                break;
            case SRC_OFFSETS:
                store_le64(p, (uint64_t)r + 1);
                break;
            case SRC_BYTES:
                *p = a->bytes[i];
                break;
            default: /* SRC_VERTEX */
                *p = 1;
                break;
            }
        }
        fwrite(buf, 1, rows * width, f);
    }
}

/* ---- the XML ------------------------------------------------------------------------------ */

static void put_data_array(FILE *f, const vtu_array *a)
{
    fprintf(f, "        <DataArray type=\"%s\" Name=\"%s\"", type_names[a->type], a->name);
    if (a->ncomp > 1)
        fprintf(f, " NumberOfComponents=\"%d\"", a->ncomp);
    fprintf(f, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)a->offset);
}

static void write_vtu(FILE *f, const void *job)
{
    const vtu_job *w = job;
    static const char *const sec_tag[] = {"PointData", "Points", "Cells"};
    fputs("<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
          "header_type=\"UInt64\">\n"
          "  <UnstructuredGrid>\n",
          f);
    fprintf(f, "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n", w->c->n, w->c->n);
    for (int s = 0; s < SEC_END; ++s) {
        fprintf(f, "      <%s>\n", sec_tag[s]);
        for (size_t k = w->sec_start[s]; k < w->sec_start[s + 1]; ++k)
            put_data_array(f, &w->a[k]);
        fprintf(f, "      </%s>\n", sec_tag[s]);
    }
    fputs("    </Piece>\n"
          "  </UnstructuredGrid>\n"
          "  <AppendedData encoding=\"raw\">\n"
          "   _",
          f);
    for (size_t k = 0; k < w->na && !ferror(f); ++k)
        put_array(f, w, &w->a[k]);
    fputs("\n  </AppendedData>\n"
          "</VTKFile>\n",
          f);
}

/* ---- the table of arrays ------------------------------------------------------------------ */

static vtu_array *push(vtu_array *a, size_t *na, const char *name, int type, int ncomp, int src)
{
    vtu_array *e = &a[(*na)++];
    memset(e, 0, sizeof *e);
    e->name = name;
    e->type = type;
    e->ncomp = ncomp;
    e->src = src;
    return e;
}

/* Fill the table in file order: PointData, Points, Cells. */
static void build_table(vtu_job *w, const uint8_t *row_status)
{
    const pst_cloud *c = w->c;
    vtu_array *a = w->a, *e;
    size_t na = 0;
    w->sec_start[SEC_POINTDATA] = 0;
    push(a, &na, "id", VTU_I64, 1, SRC_IDS);
    e = push(a, &na, "kind", VTU_U8, 1, SRC_BYTES);
    e->bytes = c->kind;
    e = push(a, &na, "V", VTU_F64, 1, SRC_DOUBLES);
    e->data[0] = c->V;
    e = push(a, &na, "h", VTU_F64, 1, SRC_DOUBLES);
    e->data[0] = c->h;
    e->fill[0] = c->h_uniform;
    e = push(a, &na, "normal", VTU_F64, 3, SRC_DOUBLES);
    for (int d = 0; d < c->dim; ++d)
        e->data[d] = c->normal[d];
    if (c->mob_ncomp > 0) {
        int diag = c->mob_ncomp > 1;
        e = push(a, &na, diag ? "M" : "m", VTU_F64, diag ? 3 : 1, SRC_DOUBLES);
        for (int m = 0; m < c->mob_ncomp; ++m)
            e->data[m] = c->mob[m];
    }
    if (row_status) {
        e = push(a, &na, "status", VTU_U8, 1, SRC_BYTES);
        e->bytes = row_status;
    }
    for (size_t k = 0; k < c->nfields; ++k) {
        e = push(a, &na, c->field_name[k], VTU_F64, 1, SRC_DOUBLES);
        e->data[0] = c->field[k];
    }
    w->sec_start[SEC_POINTS] = na;
    e = push(a, &na, "Points", VTU_F64, 3, SRC_DOUBLES);
    for (int d = 0; d < c->dim; ++d)
        e->data[d] = c->x[d];
    w->sec_start[SEC_CELLS] = na;
    push(a, &na, "connectivity", VTU_I64, 1, SRC_CONNECTIVITY);
    push(a, &na, "offsets", VTU_I64, 1, SRC_OFFSETS);
    push(a, &na, "types", VTU_U8, 1, SRC_VERTEX);
    w->sec_start[SEC_END] = na;
    w->na = na;
    uint64_t off = 0;
    for (size_t k = 0; k < na; ++k) {
        a[k].offset = off;
        off += 8 + array_bytes(&a[k], c->n);
    }
}

int pst_cloud_write_vtu(const pst_cloud *c, const char *path, const uint8_t *row_status,
                        char *err)
{
    /* a field may not take the name of another PointData array (the others are reserved
     * column names, which no field can have) */
    for (size_t k = 0; k < c->nfields; ++k) {
        const char *name = c->field_name[k];
        PST_CHECK(!strcmp(name, "normal") || (row_status && !strcmp(name, "status")) ||
                      (c->mob_ncomp > 1 && !strcmp(name, "M")),
                  PST_EINVAL, err, "%s: field '%s' has the name of one of the file's own arrays",
                  path, name);
    }
    size_t *inv;
    char msg[PST_ERRLEN] = "";
    int st = pst_cloud_input_inverse(c, &inv, msg);
    PST_CHECK(st != PST_OK, st, err, "%s: %s", path, msg);
    vtu_job job = {.c = c, .inv = inv};
    job.a = malloc((c->nfields + 12) * sizeof *job.a);
    if (!job.a) {
        pst_set_err(err, "%s: out of memory", path);
        free(inv);
        return PST_ENOMEM;
    }
    build_table(&job, row_status);
    st = pst_write_atomic(path, write_vtu, &job, err);
    free(job.a);
    free(inv);
    return st;
}
