/* Writing clouds as VTK XML files for ParaView: UnstructuredGrid (.vtu) or PolyData (.vtp),
 * appended raw or zlib-compressed (layout: docs/io.md). One table of array descriptors drives
 * both halves of the file: the XML header, which needs every array's offset into the appended
 * block before any data is written, and the appended block itself. Values are stored byte by
 * byte in little-endian order, so the file is the same on any host; rows are emitted in input
 * order (by ids) through small gather buffers, and the file goes through pst_write_atomic.
 * Fields NAME_x, NAME_y[, NAME_z] become one 3-component array NAME, fields NAME_xx..NAME_xz
 * one 6-component symmetric tensor (vtu_groups.c). */
#include "cloud_layout.h"
#include "check.h"
#include "vtu_groups.h"
#include "vtu_deflate.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

enum { VTU_F64, VTU_I64, VTU_U8 };

/* Where an array's values come from. */
enum {
    SRC_DOUBLES,     /* Float64, 1 to 6 components: data[m], or fill[m] where data[m] is NULL */
    SRC_IDS,         /* Int64: the ids                                                        */
    SRC_CONNECTIVITY,/* Int64: row r (cell r holds point r)                                   */
    SRC_OFFSETS,     /* Int64: r + 1 (end of cell r in the connectivity)                      */
    SRC_BYTES,       /* UInt8: bytes[i]                                                       */
    SRC_VERTEX       /* UInt8: 1 (VTK_VERTEX) for every cell                                  */
};

typedef struct {
    const char *name;
    int type, ncomp, src;
    const double *data[PST_VTU_MAX_COMP];
    double fill[PST_VTU_MAX_COMP];
    const uint8_t *bytes;
    unsigned char *packed; /* compressed: the array's header and blocks */
    size_t npacked;
    uint64_t offset;       /* into the appended block, from the byte after '_' */
} vtu_array;

enum { SEC_POINTDATA, SEC_POINTS, SEC_CELLS, SEC_END };

typedef struct {
    const pst_cloud *c;
    const size_t *inv;       /* inv[r] = particle of input row r */
    vtu_array *a;
    size_t na, sec_start[SEC_END + 1];
    int polydata, zlib;
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

#define VTU_CHUNK 512 /* rows per gather buffer */

/* Rows r0 .. r0 + rows - 1 of array a, as the file stores them, into buf. */
static void gather_rows(const vtu_job *w, const vtu_array *a, size_t r0, size_t rows,
                        unsigned char *buf)
{
    const pst_cloud *c = w->c;
    size_t width = (size_t)a->ncomp * type_sizes[a->type];
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
}

/* Uncompressed: a UInt64 byte count, then the values, a chunk at a time. */
static void put_array(FILE *f, const vtu_job *w, const vtu_array *a)
{
    if (a->packed) {
        fwrite(a->packed, 1, a->npacked, f);
        return;
    }
    size_t n = w->c->n, width = (size_t)a->ncomp * type_sizes[a->type];
    unsigned char buf[VTU_CHUNK * PST_VTU_MAX_COMP * 8];
    store_le64(buf, array_bytes(a, n));
    fwrite(buf, 1, 8, f);
    for (size_t r0 = 0; r0 < n && !ferror(f); r0 += VTU_CHUNK) {
        size_t rows = n - r0 < VTU_CHUNK ? n - r0 : VTU_CHUNK;
        gather_rows(w, a, r0, rows, buf);
        fwrite(buf, 1, rows * width, f);
    }
}

/* Compressed: the whole array gathered, then packed in vtkZLibDataCompressor blocks. */
static int pack_array(const vtu_job *w, vtu_array *a)
{
    size_t len = (size_t)array_bytes(a, w->c->n);
    unsigned char *raw = malloc(len ? len : 1);
    if (!raw)
        return PST_ENOMEM;
    gather_rows(w, a, 0, w->c->n, raw);
    int st = pst_vtu_zlib_pack(raw, len, &a->packed, &a->npacked);
    free(raw);
    return st;
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
    const char *dataset = w->polydata ? "PolyData" : "UnstructuredGrid";
    const char *sec_tag[] = {"PointData", "Points", w->polydata ? "Verts" : "Cells"};
    fprintf(f,
            "<?xml version=\"1.0\"?>\n"
            "<VTKFile type=\"%s\" version=\"1.0\" byte_order=\"LittleEndian\" "
            "header_type=\"UInt64\"%s>\n"
            "  <%s>\n",
            dataset, w->zlib ? " compressor=\"vtkZLibDataCompressor\"" : "", dataset);
    if (w->polydata)
        fprintf(f, "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"%zu\" NumberOfLines=\"0\" "
                   "NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n", w->c->n, w->c->n);
    else
        fprintf(f, "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n", w->c->n,
                w->c->n);
    for (int s = 0; s < SEC_END; ++s) {
        fprintf(f, "      <%s>\n", sec_tag[s]);
        for (size_t k = w->sec_start[s]; k < w->sec_start[s + 1]; ++k)
            put_data_array(f, &w->a[k]);
        fprintf(f, "      </%s>\n", sec_tag[s]);
    }
    fprintf(f,
            "    </Piece>\n"
            "  </%s>\n"
            "  <AppendedData encoding=\"raw\">\n"
            "   _",
            dataset);
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

/* The cloud's own PointData arrays: id, kind, V, h, normal, the mobility, status. */
static size_t push_own_arrays(vtu_job *w, const uint8_t *row_status)
{
    const pst_cloud *c = w->c;
    vtu_array *a = w->a, *e;
    size_t na = 0;
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
    return na;
}

/* Fill the table in file order: PointData, Points, Cells (Verts). The fields' arrays come
 * from the grouping `g`; a name met twice among the PointData arrays is PST_EINVAL. */
static int build_table(vtu_job *w, const uint8_t *row_status, const pst_vtu_groups *g,
                       const char *path, char *err)
{
    const pst_cloud *c = w->c;
    vtu_array *a = w->a, *e;
    w->sec_start[SEC_POINTDATA] = 0;
    size_t na = push_own_arrays(w, row_status), nown = na;
    for (size_t q = 0; q < g->n; ++q) {
        const pst_vtu_group *gr = &g->group[q];
        e = push(a, &na, gr->name, VTU_F64, gr->ncomp, SRC_DOUBLES);
        for (int m = 0; m < gr->ncomp; ++m)
            e->data[m] = gr->member[m] >= 0 ? c->field[gr->member[m]] : NULL;
    }
    for (size_t k = nown; k < na; ++k)
        for (size_t j = 0; j < k; ++j)
            PST_CHECK(!strcmp(a[j].name, a[k].name), PST_EINVAL, err,
                      "%s: two PointData arrays named '%s': %s and %s", path, a[k].name,
                      j < nown ? "one of the file's own arrays" : g->group[j - nown].what,
                      g->group[k - nown].what);
    w->sec_start[SEC_POINTS] = na;
    e = push(a, &na, "Points", VTU_F64, 3, SRC_DOUBLES);
    for (int d = 0; d < c->dim; ++d)
        e->data[d] = c->x[d];
    w->sec_start[SEC_CELLS] = na;
    push(a, &na, "connectivity", VTU_I64, 1, SRC_CONNECTIVITY);
    push(a, &na, "offsets", VTU_I64, 1, SRC_OFFSETS);
    if (!w->polydata)
        push(a, &na, "types", VTU_U8, 1, SRC_VERTEX);
    w->sec_start[SEC_END] = na;
    w->na = na;
    return PST_OK;
}

/* Offsets into the appended block, after packing every array when compressed. */
static int place_arrays(vtu_job *w)
{
    uint64_t off = 0;
    for (size_t k = 0; k < w->na; ++k) {
        vtu_array *a = &w->a[k];
        if (w->zlib && pack_array(w, a) != PST_OK)
            return PST_ENOMEM;
        a->offset = off;
        off += w->zlib ? a->npacked : 8 + array_bytes(a, w->c->n);
    }
    return PST_OK;
}

static int ends_with_vtp(const char *path)
{
    size_t len = strlen(path);
    return len >= 4 && strcasecmp(path + len - 4, ".vtp") == 0;
}

int pst_cloud_write_vtk(const pst_cloud *c, const char *path, const uint8_t *row_status,
                        int flags, char *err)
{
    pst_vtu_groups g;
    char msg[PST_ERRLEN] = "";
    int st = pst_vtu_group_fields(c, &g, msg);
    PST_CHECK(st != PST_OK, st, err, "%s: %s", path, msg);
    size_t *inv;
    st = pst_cloud_input_inverse(c, &inv, msg);
    if (st != PST_OK) {
        pst_vtu_groups_free(&g);
        pst_set_err(err, "%s: %s", path, msg);
        return st;
    }
    vtu_job job = {.c = c, .inv = inv, .polydata = ends_with_vtp(path),
                   .zlib = (flags & PST_VTK_ZLIB) != 0};
    job.a = calloc(g.n + 12, sizeof *job.a);
    if (!job.a) {
        pst_set_err(err, "%s: out of memory", path);
        st = PST_ENOMEM;
    }
    if (st == PST_OK)
        st = build_table(&job, row_status, &g, path, err);
    if (st == PST_OK && place_arrays(&job) != PST_OK) {
        pst_set_err(err, "%s: out of memory for the compressed arrays", path);
        st = PST_ENOMEM;
    }
    if (st == PST_OK)
        st = pst_write_atomic(path, write_vtu, &job, err);
    for (size_t k = 0; job.a && k < job.na; ++k)
        free(job.a[k].packed);
    free(job.a);
    free(inv);
    pst_vtu_groups_free(&g);
    return st;
}

int pst_cloud_write_vtu(const pst_cloud *c, const char *path, const uint8_t *row_status,
                        char *err)
{
    return pst_cloud_write_vtk(c, path, row_status, 0, err);
}
