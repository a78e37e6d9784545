/* VTU output: the files are re-read by a small parser of the appended raw format, which checks
 * the XML header, every array's type, component count, offset and UInt64 byte count, that the
 * arrays tile the appended block exactly, and every value bit for bit against the cloud in
 * input order. Also: the file does not depend on the cloud's storage order, and failed writes
 * (no such directory, a write cut short, bad ids, a field named like a file array) leave no
 * file behind. The reader: every format, zlib-compressed files made here with compress2
 * (several blocks, a short last one, vector and tensor arrays), and damaged files, each error
 * text asserted. tests/vtu_roundtrip.py reads files with VTK's own reader. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp, setrlimit, opendir */

#include "check.h"
#include "support.h"
#include "pstencil.h"

#include <dirent.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

static char dir[64];

static const char *path_of(const char *name)
{
    return test_path_in(dir, name);
}

/* Temporary files the writer might have left behind. */
static int leftovers(void)
{
    return test_count_temporaries(dir);
}

/* ---- a parser of the files the writer produces ------------------------------------------- */

enum { PART_POINTDATA, PART_POINTS, PART_CELLS };

typedef struct {
    char name[80], type[16];
    int ncomp, part;
    uint64_t offset;
} parsed_array;

typedef struct {
    unsigned char *buf;    /* the whole file, NUL-terminated */
    size_t len;
    size_t npoints, ncells;
    parsed_array a[64];
    size_t na;
    const unsigned char *data; /* the byte after '_' */
    int ok;                    /* every structural check passed */
} vtu_file;

static uint64_t load_le64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int b = 7; b >= 0; --b)
        v = v << 8 | p[b];
    return v;
}

static double load_f64(const unsigned char *p)
{
    uint64_t u = load_le64(p);
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
}

/* Copy the value of attribute `key` of the element [start, end) into out; 0 when absent. */
static int attr(const char *start, const char *end, const char *key, char *out, size_t cap)
{
    char pat[32];
    snprintf(pat, sizeof pat, " %s=\"", key);
    const char *p = strstr(start, pat);
    if (!p || p >= end)
        return 0;
    p += strlen(pat);
    const char *q = strchr(p, '"');
    if (!q || q >= end || (size_t)(q - p) >= cap)
        return 0;
    memcpy(out, p, (size_t)(q - p));
    out[q - p] = '\0';
    return 1;
}

static size_t type_size(const char *type)
{
    return !strcmp(type, "Float64") || !strcmp(type, "Int64") ? 8 : !strcmp(type, "UInt8") ? 1 : 0;
}

#define PARSE_CHECK(cond)                                                                      \
    do {                                                                                       \
        CHECK(cond);                                                                           \
        if (!(cond))                                                                           \
            return;                                                                            \
    } while (0)

static void parse_into(vtu_file *v)
{
    char *text = (char *)v->buf;
    static const char head[] =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
        "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n";
    PARSE_CHECK(!strncmp(text, head, strlen(head)));
    const char *app = strstr(text, "<AppendedData encoding=\"raw\">");
    PARSE_CHECK(app != NULL);
    const char *piece = strstr(text, "<Piece ");
    PARSE_CHECK(piece && piece < app);
    PARSE_CHECK(sscanf(piece, "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">", &v->npoints,
                       &v->ncells) == 2);
    const char *part_tag[3][2] = {{"<PointData>", "</PointData>"},
                                  {"<Points>", "</Points>"},
                                  {"<Cells>", "</Cells>"}};
    const char *lo[3], *hi[3];
    for (int s = 0; s < 3; ++s) {
        lo[s] = strstr(text, part_tag[s][0]);
        hi[s] = strstr(text, part_tag[s][1]);
        PARSE_CHECK(lo[s] && hi[s] && lo[s] < hi[s] && hi[s] < app);
    }
    for (const char *p = strstr(text, "<DataArray "); p && p < app;
         p = strstr(p + 1, "<DataArray ")) {
        PARSE_CHECK(v->na < 64);
        parsed_array *a = &v->a[v->na++];
        const char *end = strstr(p, "/>");
        PARSE_CHECK(end && end < app);
        char ncomp[16] = "1", format[16] = "", offset[32] = "";
        PARSE_CHECK(attr(p, end, "type", a->type, sizeof a->type));
        PARSE_CHECK(attr(p, end, "Name", a->name, sizeof a->name));
        PARSE_CHECK(attr(p, end, "format", format, sizeof format) && !strcmp(format, "appended"));
        PARSE_CHECK(attr(p, end, "offset", offset, sizeof offset));
        attr(p, end, "NumberOfComponents", ncomp, sizeof ncomp);
        a->ncomp = atoi(ncomp);
        a->offset = strtoull(offset, NULL, 10);
        a->part = -1;
        for (int s = 0; s < 3; ++s)
            if (p > lo[s] && p < hi[s])
                a->part = s;
        PARSE_CHECK(a->part >= 0 && type_size(a->type) > 0 && a->ncomp >= 1);
    }
    /* the appended block: '_' after white space, then the arrays back to back */
    const char *q = app + strlen("<AppendedData encoding=\"raw\">");
    while (*q == ' ' || *q == '\n')
        ++q;
    PARSE_CHECK(*q == '_');
    v->data = (const unsigned char *)q + 1;
    size_t avail = v->len - (size_t)(v->data - v->buf);
    uint64_t at = 0;
    for (size_t k = 0; k < v->na; ++k) {
        parsed_array *a = &v->a[k];
        PARSE_CHECK(a->offset == at);
        PARSE_CHECK(at + 8 <= avail);
        uint64_t bytes = load_le64(v->data + at);
        CHECK_INT(bytes, (uint64_t)v->npoints * (uint64_t)a->ncomp * type_size(a->type));
        PARSE_CHECK(bytes == (uint64_t)v->npoints * (uint64_t)a->ncomp * type_size(a->type));
        at += 8 + bytes;
        PARSE_CHECK(at <= avail);
    }
    static const char tail[] = "\n  </AppendedData>\n</VTKFile>\n";
    PARSE_CHECK(avail - at == strlen(tail) && !memcmp(v->data + at, tail, strlen(tail)));
    v->ok = 1;
}

static int parse(vtu_file *v, const char *path)
{
    memset(v, 0, sizeof *v);
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    v->buf = malloc((size_t)len + 1);
    v->len = v->buf ? fread(v->buf, 1, (size_t)len, f) : 0;
    fclose(f);
    if (!v->buf || v->len != (size_t)len)
        return 0;
    v->buf[v->len] = '\0';
    parse_into(v);
    return v->ok;
}

static const parsed_array *find(const vtu_file *v, const char *name)
{
    for (size_t k = 0; k < v->na; ++k)
        if (!strcmp(v->a[k].name, name))
            return &v->a[k];
    return NULL;
}

/* The values of an array (after its byte count). */
static const unsigned char *values(const vtu_file *v, const parsed_array *a)
{
    return v->data + a->offset + 8;
}

/* "name:type:ncomp" of every array, in file order, parts separated by '|'. */
static void signature(const vtu_file *v, char *out, size_t cap)
{
    size_t used = 0;
    out[0] = '\0';
    for (size_t k = 0; k < v->na; ++k) {
        const char *sep = k == 0 ? "" : v->a[k].part != v->a[k - 1].part ? "|" : ",";
        used += (size_t)snprintf(out + used, cap - used, "%s%s:%s:%d", sep, v->a[k].name,
                                 v->a[k].type, v->a[k].ncomp);
        if (used >= cap)
            return;
    }
}

/* ---- clouds ------------------------------------------------------------------------------ */

/* A jittered cell-centred cloud with every kind, per-particle (or uniform) h, mobility and two
 * fields, permuted so that its order differs from the input order. Hard values on purpose: -0,
 * subnormals, huge and tiny magnitudes. */
static pst_cloud *make_cloud(int dim, int mob, int per_particle_h)
{
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = dim;
    o.s0 = 0.25;
    o.jitter = 0.3;
    o.seed = 7;
    pst_cloud *c;
    if (pst_cloud_cell_centred(&c, &o, NULL) != PST_OK)
        return NULL;
    size_t n = pst_cloud_size(c);
    double *h = per_particle_h ? pst_cloud_h_per_particle(c) : NULL, *u, *rhs;
    pst_cloud_set_mobility(c, mob, NULL);
    pst_cloud_add_field(c, "u", &u, NULL);
    pst_cloud_add_field(c, "rhs_2", &rhs, NULL);
    for (size_t i = 0; i < n; ++i) {
        if (h)
            h[i] = 0.3 + (double)i / 3;
        pst_cloud_volume(c)[i] = 1.0 / (double)(i + 3);
        u[i] = i % 4 == 0 ? -0.0 : i % 4 == 1 ? 4.9e-320 : i % 4 == 2 ? 1e300 : -1.0 / 7;
        rhs[i] = sin((double)i) * 1e-200;
        for (int m = 0; m < mob; ++m)
            pst_cloud_mobility(c, m)[i] = 1 + (double)(i + (size_t)m) / 9;
    }
    pst_cloud_kinds(c)[n - 1] = PST_NEUMANN;
    pst_cloud_kinds(c)[n - 2] = PST_NEUMANN;
    uint32_t *perm = malloc(n * sizeof *perm);
    for (size_t i = 0; i < n; ++i)
        perm[i] = (uint32_t)((i * 7 + 3) % n); /* n is not a multiple of 7 below */
    CHECK_INT(pst_cloud_permute(c, perm, NULL), PST_OK);
    free(perm);
    return c;
}

static uint8_t *make_status(const pst_cloud *c)
{
    size_t n = pst_cloud_size(c);
    uint8_t *s = malloc(n ? n : 1);
    for (size_t i = 0; i < n; ++i)
        s[i] = (uint8_t)((i * 3 + 1) % PST_ROW_NSTATUS);
    return s;
}

/* Every value of the file against the cloud, bit for bit, row r = the particle with id r. */
static void check_values(const vtu_file *v, pst_cloud *c, const uint8_t *status)
{
    size_t n = pst_cloud_size(c);
    int dim = pst_cloud_dim(c), mob = pst_cloud_mobility_ncomp(c);
    size_t *inv = malloc((n ? n : 1) * sizeof *inv);
    for (size_t i = 0; i < n; ++i)
        inv[pst_cloud_ids(c)[i]] = i;
    const unsigned char *id = values(v, find(v, "id")), *kind = values(v, find(v, "kind")),
                        *V = values(v, find(v, "V")), *h = values(v, find(v, "h")),
                        *nrm = values(v, find(v, "normal")),
                        *pts = values(v, find(v, "Points")),
                        *conn = values(v, find(v, "connectivity")),
                        *off = values(v, find(v, "offsets")),
                        *types = values(v, find(v, "types"));
    const parsed_array *ma = find(v, mob == 1 ? "m" : "M"), *sa = find(v, "status");
    const unsigned char *m = mob ? values(v, ma) : NULL, *st = status ? values(v, sa) : NULL;
    size_t bad = 0;
#define SAME(a, b) (bad += memcmp(&(double){a}, &(double){b}, sizeof(double)) != 0)
    for (size_t r = 0; r < n; ++r) {
        size_t i = inv[r];
        bad += load_le64(id + 8 * r) != r;
        bad += kind[r] != pst_cloud_kinds(c)[i];
        SAME(load_f64(V + 8 * r), pst_cloud_volume(c)[i]);
        const double *ha = pst_cloud_h_array(c);
        SAME(load_f64(h + 8 * r), ha ? ha[i] : pst_cloud_h_uniform(c));
        for (int d = 0; d < 3; ++d) {
            SAME(load_f64(pts + 24 * r + 8 * (size_t)d), d < dim ? pst_cloud_coord(c, d)[i] : 0.0);
            SAME(load_f64(nrm + 24 * r + 8 * (size_t)d), d < dim ? pst_cloud_normal(c, d)[i] : 0.0);
        }
        if (mob == 1)
            SAME(load_f64(m + 8 * r), pst_cloud_mobility(c, 0)[i]);
        for (int d = 0; mob > 1 && d < 3; ++d)
            SAME(load_f64(m + 24 * r + 8 * (size_t)d), d < mob ? pst_cloud_mobility(c, d)[i] : 0.0);
        if (status)
            bad += st[r] != status[i];
        for (size_t k = 0; k < pst_cloud_nfields(c); ++k)
            SAME(load_f64(values(v, find(v, pst_cloud_field_name(c, k))) + 8 * r),
                 pst_cloud_field(c, k)[i]);
        bad += load_le64(conn + 8 * r) != r;
        bad += load_le64(off + 8 * r) != r + 1;
        bad += types[r] != 1;
    }
#undef SAME
    CHECK_INT(bad, 0);
    free(inv);
}

static void check_file(const char *name, int dim, int mob, int per_particle_h, int with_status,
                       const char *expect_sig)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *c = make_cloud(dim, mob, per_particle_h);
    CHECK(c != NULL);
    if (!c)
        return;
    uint8_t *status = with_status ? make_status(c) : NULL;
    CHECK_INT(pst_cloud_write_vtu(c, path_of(name), status, err), PST_OK);
    vtu_file v;
    CHECK(parse(&v, path_of(name)));
    if (v.ok) {
        CHECK_INT(v.npoints, pst_cloud_size(c));
        CHECK_INT(v.ncells, pst_cloud_size(c));
        char sig[1024];
        signature(&v, sig, sizeof sig);
        CHECK(!strcmp(sig, expect_sig));
        if (strcmp(sig, expect_sig))
            fprintf(stderr, "  arrays:   %s\n  expected: %s\n", sig, expect_sig);
        else
            check_values(&v, c, status);
    }

    /* the same particles stored in another order (status moving with them) give the same
     * bytes: the file follows the input order, not the storage order */
    size_t n = pst_cloud_size(c);
    uint32_t *perm = malloc(n * sizeof *perm);
    uint8_t *status2 = with_status ? malloc(n) : NULL;
    for (size_t i = 0; i < n; ++i)
        perm[i] = (uint32_t)(n - 1 - i);
    for (size_t i = 0; status2 && i < n; ++i)
        status2[i] = status[perm[i]];
    CHECK_INT(pst_cloud_permute(c, perm, NULL), PST_OK);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("again.vtu"), status2, err), PST_OK);
    vtu_file w;
    CHECK(parse(&w, path_of("again.vtu")));
    CHECK(v.len == w.len && v.buf && w.buf && !memcmp(v.buf, w.buf, v.len));
    free(v.buf);
    free(w.buf);
    free(perm);
    free(status);
    free(status2);
    CHECK_INT(leftovers(), 0);
    pst_cloud_destroy(c);
}

static void test_layouts(void)
{
    /* 2D, diagonal mobility, per-particle h, status */
    check_file("d2.vtu", 2, 2, 1, 1,
               "id:Int64:1,kind:UInt8:1,V:Float64:1,h:Float64:1,normal:Float64:3,M:Float64:3,"
               "status:UInt8:1,u:Float64:1,rhs_2:Float64:1|Points:Float64:3|"
               "connectivity:Int64:1,offsets:Int64:1,types:UInt8:1");
    /* 3D, scalar mobility, uniform h, status */
    check_file("s3.vtu", 3, 1, 0, 1,
               "id:Int64:1,kind:UInt8:1,V:Float64:1,h:Float64:1,normal:Float64:3,m:Float64:1,"
               "status:UInt8:1,u:Float64:1,rhs_2:Float64:1|Points:Float64:3|"
               "connectivity:Int64:1,offsets:Int64:1,types:UInt8:1");
    /* 3D, diagonal mobility, no status */
    check_file("d3.vtu", 3, 3, 1, 0,
               "id:Int64:1,kind:UInt8:1,V:Float64:1,h:Float64:1,normal:Float64:3,M:Float64:3,"
               "u:Float64:1,rhs_2:Float64:1|Points:Float64:3|"
               "connectivity:Int64:1,offsets:Int64:1,types:UInt8:1");
    /* 2D, no mobility, no status */
    check_file("p2.vtu", 2, 0, 0, 0,
               "id:Int64:1,kind:UInt8:1,V:Float64:1,h:Float64:1,normal:Float64:3,"
               "u:Float64:1,rhs_2:Float64:1|Points:Float64:3|"
               "connectivity:Int64:1,offsets:Int64:1,types:UInt8:1");
}

/* A cloud of one particle with known values: the exact bytes of its appended block. */
static void test_exact_bytes(void)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *c;
    CHECK_INT(pst_cloud_create(&c, 2, 1, NULL), PST_OK);
    pst_cloud_coord(c, 0)[0] = 1.5;
    pst_cloud_coord(c, 1)[0] = -2.0;
    pst_cloud_set_h_uniform(c, 0.25, NULL);
    pst_cloud_kinds(c)[0] = PST_DIRICHLET;
    CHECK_INT(pst_cloud_write_vtu(c, path_of("one.vtu"), NULL, err), PST_OK);
    vtu_file v;
    CHECK(parse(&v, path_of("one.vtu")));
    /* id, kind, V, h, normal, Points, connectivity, offsets, types */
    static const uint64_t expect_off[] = {0, 16, 25, 41, 57, 89, 121, 137, 153};
    CHECK_INT(v.na, 9);
    for (size_t k = 0; k < v.na && k < 9; ++k)
        CHECK_INT(v.a[k].offset, expect_off[k]);
    if (v.ok && v.na == 9) {
        const unsigned char *p = values(&v, &v.a[5]);
        /* 1.5 = 0x3FF8000000000000, -2 = 0xC000000000000000, little-endian */
        static const unsigned char pts[24] = {0, 0, 0, 0, 0, 0, 0xF8, 0x3F,
                                              0, 0, 0, 0, 0, 0, 0, 0xC0};
        CHECK(!memcmp(p, pts, sizeof pts));
        CHECK_INT(values(&v, &v.a[1])[0], PST_DIRICHLET);
        CHECK(load_f64(values(&v, &v.a[3])) == 0.25);
        CHECK_INT(load_le64(values(&v, &v.a[7])), 1);
        CHECK_INT(values(&v, &v.a[8])[0], 1);
        CHECK_INT(load_le64(v.data + 153), 1); /* the last byte count */
    }
    free(v.buf);
    pst_cloud_destroy(c);

    /* an empty cloud: every array is a bare zero byte count */
    CHECK_INT(pst_cloud_create(&c, 3, 0, NULL), PST_OK);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("empty.vtu"), NULL, err), PST_OK);
    CHECK(parse(&v, path_of("empty.vtu")));
    CHECK_INT(v.npoints, 0);
    CHECK_INT(v.na, 9);
    CHECK_INT(v.a[v.na ? v.na - 1 : 0].offset, 8 * 8);
    free(v.buf);
    pst_cloud_destroy(c);
}

/* The writer under test_under_file_limit: a cloud, its row status, the path, the message. */
typedef struct {
    const pst_cloud *c;
    const uint8_t *status;
    const char *path;
    char *err;
} write_job;

static int write_keep(const void *job)
{
    const write_job *j = job;
    return pst_cloud_write_vtu(j->c, j->path, j->status, j->err);
}

static void test_failures(void)
{
    char err[PST_ERRLEN] = "";
    struct stat sb;
    pst_cloud *c = make_cloud(2, 1, 1);
    uint8_t *status = make_status(c);

    /* into a directory that does not exist: EIO naming the path, and nothing is created */
    const char *p = path_of("no_such_dir/out.vtu");
    CHECK_INT(pst_cloud_write_vtu(c, p, status, err), PST_EIO);
    CHECK(strstr(err, "no_such_dir/out.vtu") != NULL);
    CHECK(stat(path_of("no_such_dir"), &sb) != 0);
    CHECK(stat(p, &sb) != 0);

    /* a write that fails half-way (file-size limit) leaves the old file as it was */
    static const char old[] = "old contents\n";
    CHECK_INT(test_write_text(path_of("keep.vtu"), old), 0);
    write_job job = {c, status, path_of("keep.vtu"), err};
    CHECK_INT(test_under_file_limit(2048 /* the header fits, the data does not */, write_keep,
                                    &job),
              PST_EIO);
    CHECK(strstr(err, "keep.vtu") != NULL);
    CHECK(test_file_holds(path_of("keep.vtu"), old));
    CHECK_INT(leftovers(), 0);

    /* a directory in the way is refused before anything is written */
    mkdir(path_of("a_dir"), 0755);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("a_dir"), status, err), PST_EIO);
    CHECK(strstr(err, "is a directory") != NULL);
    CHECK_INT(leftovers(), 0);
    rmdir(path_of("a_dir"));

    /* a field named like one of the file's arrays */
    double *x;
    CHECK_INT(pst_cloud_add_field(c, "status", &x, NULL), PST_OK);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("clash.vtu"), status, err), PST_EINVAL);
    CHECK(strstr(err, "clash.vtu") && strstr(err, "'status'"));
    CHECK(stat(path_of("clash.vtu"), &sb) != 0);
    /* ... which is fine when the file has no status array */
    CHECK_INT(pst_cloud_write_vtu(c, path_of("clash.vtu"), NULL, err), PST_OK);
    CHECK(unlink(path_of("clash.vtu")) == 0);
    CHECK_INT(pst_cloud_add_field(c, "normal", &x, NULL), PST_OK);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("clash.vtu"), NULL, err), PST_EINVAL);
    CHECK(strstr(err, "'normal'") != NULL);
    CHECK(stat(path_of("clash.vtu"), &sb) != 0);

    free(status);
    pst_cloud_destroy(c);

    /* ids that are not a permutation cannot give an input order */
    c = make_cloud(3, 0, 0);
    pst_cloud_ids(c)[0] = pst_cloud_ids(c)[1];
    CHECK_INT(pst_cloud_write_vtu(c, path_of("ids.vtu"), NULL, err), PST_EINVAL);
    CHECK(strstr(err, "ids.vtu") && strstr(err, "permutation"));
    CHECK(stat(path_of("ids.vtu"), &sb) != 0);
    CHECK_INT(leftovers(), 0);
    pst_cloud_destroy(c);
}

/* ---- reading (pst_cloud_read_vtu) -------------------------------------------------------- */

static int same_bits(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* The cloud read back against the one written: particle ids[i] of `r` is particle i of `c`
 * (the file is in input order), every value bit for bit. */
static void check_same_cloud(pst_cloud *c, pst_cloud *r)
{
    CHECK(r != NULL);
    if (!r)
        return;
    size_t n = pst_cloud_size(c);
    int dim = pst_cloud_dim(c), mob = pst_cloud_mobility_ncomp(c);
    CHECK_INT(pst_cloud_size(r), n);
    CHECK_INT(pst_cloud_dim(r), dim);
    CHECK_INT(pst_cloud_mobility_ncomp(r), mob);
    CHECK_INT(pst_cloud_nfields(r), pst_cloud_nfields(c));
    CHECK_INT(pst_cloud_h_is_uniform(r), pst_cloud_h_is_uniform(c));
    if (pst_cloud_size(r) != n || pst_cloud_dim(r) != dim || pst_cloud_mobility_ncomp(r) != mob ||
        pst_cloud_nfields(r) != pst_cloud_nfields(c))
        return;
    for (size_t k = 0; k < pst_cloud_nfields(c); ++k)
        CHECK(!strcmp(pst_cloud_field_name(r, k), pst_cloud_field_name(c, k)));
    size_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
        size_t j = (size_t)pst_cloud_ids(c)[i];
        bad += pst_cloud_ids(r)[j] != (int64_t)j;
        for (int d = 0; d < dim; ++d) {
            bad += !same_bits(pst_cloud_coord(r, d)[j], pst_cloud_coord(c, d)[i]);
            bad += !same_bits(pst_cloud_normal(r, d)[j], pst_cloud_normal(c, d)[i]);
        }
        bad += !same_bits(pst_cloud_volume(r)[j], pst_cloud_volume(c)[i]);
        const double *hc = pst_cloud_h_array(c), *hr = pst_cloud_h_array(r);
        bad += !same_bits(hr ? hr[j] : pst_cloud_h_uniform(r), hc ? hc[i] : pst_cloud_h_uniform(c));
        bad += pst_cloud_kinds(r)[j] != pst_cloud_kinds(c)[i];
        for (int m = 0; m < mob; ++m)
            bad += !same_bits(pst_cloud_mobility(r, m)[j], pst_cloud_mobility(c, m)[i]);
        for (size_t k = 0; k < pst_cloud_nfields(c); ++k)
            bad += !same_bits(pst_cloud_field(r, k)[j], pst_cloud_field(c, k)[i]);
    }
    CHECK_INT(bad, 0);
}

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long l = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)l + 1);
    *len = b ? fread(b, 1, (size_t)l, f) : 0;
    fclose(f);
    return b;
}

static void spit(const char *path, const void *buf, size_t len)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (!f)
        return;
    CHECK_INT(fwrite(buf, 1, len, f), len);
    fclose(f);
}

/* Write and read back: every layout, bit for bit, with the input order restored. */
static void test_read_roundtrip(void)
{
    static const int cases[][4] = {/* dim, mobility, per-particle h, status */
                                   {2, 2, 1, 1}, {2, 1, 0, 0}, {2, 0, 1, 0}, {3, 3, 1, 1},
                                   {3, 1, 0, 1}, {3, 0, 0, 0}};
    char err[PST_ERRLEN] = "";
    for (size_t t = 0; t < sizeof cases / sizeof *cases; ++t) {
        pst_cloud *c = make_cloud(cases[t][0], cases[t][1], cases[t][2]), *r = NULL;
        uint8_t *status = cases[t][3] ? make_status(c) : NULL;
        CHECK_INT(pst_cloud_write_vtu(c, path_of("rt.vtu"), status, err), PST_OK);
        CHECK_INT(pst_cloud_read_vtu(&r, path_of("rt.vtu"), err), PST_OK);
        check_same_cloud(c, r);
        pst_cloud_destroy(r);
        free(status);
        pst_cloud_destroy(c);
    }
    /* no optional array at all: kind interior, normals 0, no mobility, no fields */
    pst_cloud *c, *r = NULL;
    CHECK_INT(pst_cloud_create(&c, 3, 4, NULL), PST_OK);
    for (size_t i = 0; i < 4; ++i)
        for (int d = 0; d < 3; ++d)
            pst_cloud_coord(c, d)[i] = (double)((i >> d) & 1) + 0.5 * (double)d;
    CHECK_INT(pst_cloud_write_vtu(c, path_of("plain.vtu"), NULL, err), PST_OK);
    CHECK_INT(pst_cloud_read_vtu(&r, path_of("plain.vtu"), err), PST_OK);
    check_same_cloud(c, r);
    pst_cloud_destroy(r);
    pst_cloud_destroy(c);

    /* an empty cloud reads back empty (2D: no z differs from 0) */
    CHECK_INT(pst_cloud_create(&c, 3, 0, NULL), PST_OK);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("empty.vtu"), NULL, err), PST_OK);
    CHECK_INT(pst_cloud_read_vtu(&r, path_of("empty.vtu"), err), PST_OK);
    CHECK(r && pst_cloud_size(r) == 0 && pst_cloud_dim(r) == 2);
    pst_cloud_destroy(r);
    pst_cloud_destroy(c);

    /* the file's ids decide the order: reverse them in the file, and row k becomes particle
     * n-1-k (the particle with id k in the written cloud) */
    c = make_cloud(2, 2, 1);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("ids.vtu"), NULL, err), PST_OK);
    vtu_file v;
    CHECK(parse(&v, path_of("ids.vtu")));
    size_t n = pst_cloud_size(c);
    if (v.ok) {
        unsigned char *id = v.buf + (v.data - v.buf) + find(&v, "id")->offset + 8;
        for (size_t k = 0; k < n; ++k)
            for (int b = 0; b < 8; ++b)
                id[8 * k + (size_t)b] = (unsigned char)((uint64_t)(n - 1 - k) >> (8 * b));
        spit(path_of("ids.vtu"), v.buf, v.len);
    }
    free(v.buf);
    CHECK_INT(pst_cloud_read_vtu(&r, path_of("ids.vtu"), err), PST_OK);
    if (r) {
        size_t bad = 0;
        for (size_t i = 0; i < n; ++i) {
            size_t j = n - 1 - (size_t)pst_cloud_ids(c)[i];
            bad += !same_bits(pst_cloud_coord(r, 0)[j], pst_cloud_coord(c, 0)[i]);
            bad += !same_bits(pst_cloud_coord(r, 1)[j], pst_cloud_coord(c, 1)[i]);
            bad += !same_bits(pst_cloud_h_array(r)[j], pst_cloud_h_array(c)[i]);
            bad += !same_bits(pst_cloud_mobility(r, 1)[j], pst_cloud_mobility(c, 1)[i]);
            bad += !same_bits(pst_cloud_field(r, 0)[j], pst_cloud_field(c, 0)[i]);
            bad += pst_cloud_ids(r)[j] != (int64_t)j;
        }
        CHECK_INT(bad, 0);
    }
    pst_cloud_destroy(r);
    pst_cloud_destroy(c);
}

/* A hand-written ascii file: 2D (every z is 0), ids 2, 0, 1, Int32 kinds, Float32 h, a
 * comment, single quotes, a hex float, an ignored status and an ignored Cells section. */
static const char ascii_vtu[] =
    "<?xml version=\"1.0\"?>\n"
    "<!-- written by hand -->\n"
    "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    "  <UnstructuredGrid>\n"
    "    <Piece NumberOfPoints=\"3\" NumberOfCells=\"0\">\n"
    "      <PointData Scalars=\"V\">\n"
    "        <DataArray type=\"Float64\" Name=\"V\" format=\"ascii\">0.5 0.25 1e-3</DataArray>\n"
    "        <DataArray type=\"Float32\" Name=\"h\" format=\"ascii\">0.5 0.5 0.5</DataArray>\n"
    "        <DataArray type=\"Int32\" Name=\"kind\" format=\"ascii\">0 2 1</DataArray>\n"
    "        <DataArray type=\"Int64\" Name=\"id\" format=\"ascii\">2 0 1</DataArray>\n"
    "        <DataArray type=\"Float64\" Name=\"normal\" NumberOfComponents=\"3\" "
    "format=\"ascii\">0 0 0  1 0 0  0 -1 7</DataArray>\n"
    "        <DataArray type=\"Float64\" Name=\"M\" NumberOfComponents=\"3\" "
    "format=\"ascii\">1 2 3 4 5 6 7 8 9</DataArray>\n"
    "        <DataArray type=\"UInt8\" Name=\"status\" format=\"ascii\">9 9 9</DataArray>\n"
    "        <DataArray type=\"Float64\" Name=\"T\" format='ascii'>\n"
    "          -1.5\n"
    "          2.5 0x1p-3\n"
    "        </DataArray>\n"
    "      </PointData>\n"
    "      <Points>\n"
    "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n"
    "          0 0 0 1 0 0 0 1 0\n"
    "          <InformationKey name=\"L2_NORM_RANGE\" location=\"vtkDataArray\" length=\"2\">\n"
    "            <Value index=\"0\">0</Value><Value index=\"1\">1</Value>\n"
    "          </InformationKey>\n"
    "        </DataArray>\n"
    "      </Points>\n"
    "      <Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    "</DataArray></Cells>\n"
    "    </Piece>\n"
    "  </UnstructuredGrid>\n"
    "</VTKFile>\n";

/* The ascii file with the first `from` replaced by `to`, written as `name`. */
static const char *ascii_variant(const char *name, const char *from, const char *to)
{
    static char buf[sizeof ascii_vtu + 512];
    const char *at = from ? strstr(ascii_vtu, from) : NULL;
    CHECK(!from || at);
    if (!at)
        snprintf(buf, sizeof buf, "%s", ascii_vtu);
    else
        snprintf(buf, sizeof buf, "%.*s%s%s", (int)(at - ascii_vtu), ascii_vtu, to,
                 at + strlen(from));
    spit(path_of(name), buf, strlen(buf));
    return path_of(name);
}

/* Replace the first `from` of the NUL-terminated buf (cap bytes) by `to`. */
static void replace_once(char *buf, size_t cap, const char *from, const char *to)
{
    char *at = strstr(buf, from);
    size_t lf = strlen(from), lt = strlen(to);
    CHECK(at && strlen(buf) - lf + lt < cap);
    if (!at || strlen(buf) - lf + lt >= cap)
        return;
    memmove(at + lt, at + lf, strlen(at + lf) + 1);
    memcpy(at, to, lt);
}

static void b64_encode(const unsigned char *in, size_t len, char *out)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t o = 0;
    for (size_t i = 0; i < len; i += 3) {
        unsigned v = (unsigned)in[i] << 16 | (i + 1 < len ? (unsigned)in[i + 1] << 8 : 0) |
                     (i + 2 < len ? in[i + 2] : 0);
        out[o++] = tab[v >> 18 & 63];
        out[o++] = tab[v >> 12 & 63];
        out[o++] = i + 1 < len ? tab[v >> 6 & 63] : '=';
        out[o++] = i + 2 < len ? tab[v & 63] : '=';
    }
    out[o] = '\0';
}

/* count values of `size` bytes (little- or big-endian) after a byte-count header of hs bytes */
static size_t block(unsigned char *out, int hs, int big, const void *vals, size_t count,
                    int size)
{
    uint64_t bytes = (uint64_t)count * (uint64_t)size;
    for (int b = 0; b < hs; ++b)
        out[big ? hs - 1 - b : b] = (unsigned char)(bytes >> (8 * b));
    const unsigned char *v = vals;
    for (size_t k = 0; k < count; ++k)
        for (int b = 0; b < size; ++b) {
            /* the host is little-endian (x86-64, aarch64) */
            out[hs + k * (size_t)size + (size_t)b] =
                v[k * (size_t)size + (size_t)(big ? size - 1 - b : b)];
        }
    return (size_t)hs + (size_t)bytes;
}

static void test_read_formats(void)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *r = NULL;

    /* ascii */
    CHECK_INT(pst_cloud_read_vtu(&r, ascii_variant("ascii.vtu", NULL, NULL), err), PST_OK);
    CHECK(r != NULL);
    if (r) {
        CHECK_INT(pst_cloud_size(r), 3);
        CHECK_INT(pst_cloud_dim(r), 2);
        CHECK(pst_cloud_h_is_uniform(r) && pst_cloud_h_uniform(r) == 0.5);
        CHECK_INT(pst_cloud_mobility_ncomp(r), 2);
        CHECK_INT(pst_cloud_nfields(r), 1);
        CHECK(!strcmp(pst_cloud_field_name(r, 0), "T"));
        /* particle id[k] = row k: rows 0, 1, 2 are particles 2, 0, 1 */
        static const double x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, V[3] = {0.25, 1e-3, 0.5},
                            ny[3] = {0, -1, 0}, mx[3] = {4, 7, 1}, my[3] = {5, 8, 2},
                            T[3] = {2.5, 0.125, -1.5};
        static const int kind[3] = {2, 1, 0};
        for (size_t i = 0; i < 3; ++i) {
            CHECK(pst_cloud_coord(r, 0)[i] == x[i] && pst_cloud_coord(r, 1)[i] == y[i]);
            CHECK(pst_cloud_volume(r)[i] == V[i]);
            CHECK_INT(pst_cloud_kinds(r)[i], kind[i]);
            CHECK(pst_cloud_normal(r, 1)[i] == ny[i]);
            CHECK(pst_cloud_mobility(r, 0)[i] == mx[i] && pst_cloud_mobility(r, 1)[i] == my[i]);
            CHECK(pst_cloud_field(r, 0)[i] == T[i]);
            CHECK_INT(pst_cloud_ids(r)[i], i);
        }
        CHECK_INT(pst_cloud_validate(r, NULL), PST_OK);
    }
    pst_cloud_destroy(r);

    /* inline base64 ("binary"), UInt32 headers, Float32 points, 3D, a scalar mobility */
    {
        const float pts[9] = {0, 0, 0, 1, 0, 0.5f, 0, 1, -0.25f};
        const double V[3] = {1, 2, 3}, h[3] = {0.1, 0.2, 0.3}, m[3] = {4, 5, 6};
        const uint8_t kind[3] = {1, 0, 1}; /* no normals: no Neumann particle */
        unsigned char raw[128];
        char b64[5][200];
        block(raw, 4, 0, pts, 9, 4);
        b64_encode(raw, 4 + 36, b64[0]);
        block(raw, 4, 0, V, 3, 8);
        b64_encode(raw, 4 + 24, b64[1]);
        block(raw, 4, 0, h, 3, 8);
        b64_encode(raw, 4 + 24, b64[2]);
        block(raw, 4, 0, m, 3, 8);
        b64_encode(raw, 4 + 24, b64[3]);
        block(raw, 4, 0, kind, 3, 1);
        b64_encode(raw, 4 + 3, b64[4]);
        char file[2048];
        snprintf(file, sizeof file,
                 "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
                 "header_type=\"UInt32\"><UnstructuredGrid><Piece NumberOfPoints=\"3\">"
                 "<PointData>"
                 "<DataArray type=\"Float64\" Name=\"V\" format=\"binary\">\n  %s\n</DataArray>"
                 "<DataArray type=\"Float64\" Name=\"h\" format=\"binary\">%s</DataArray>"
                 "<DataArray type=\"Float64\" Name=\"m\" format=\"binary\">%s</DataArray>"
                 "<DataArray type=\"UInt8\" Name=\"kind\" format=\"binary\">%s</DataArray>"
                 "</PointData><Points>"
                 "<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"binary\">%s"
                 "</DataArray></Points></Piece></UnstructuredGrid></VTKFile>\n",
                 b64[1], b64[2], b64[3], b64[4], b64[0]);
        spit(path_of("b64.vtu"), file, strlen(file));
        CHECK_INT(pst_cloud_read_vtu(&r, path_of("b64.vtu"), err), PST_OK);
        CHECK(r && pst_cloud_dim(r) == 3 && pst_cloud_size(r) == 3);
        for (size_t i = 0; r && i < 3; ++i) {
            for (int d = 0; d < 3; ++d)
                CHECK(pst_cloud_coord(r, d)[i] == (double)pts[3 * i + (size_t)d]);
            CHECK(pst_cloud_volume(r)[i] == V[i] && pst_cloud_h_array(r)[i] == h[i]);
            CHECK(pst_cloud_mobility(r, 0)[i] == m[i]);
            CHECK_INT(pst_cloud_kinds(r)[i], kind[i]);
        }
        pst_cloud_destroy(r);

        /* the same data as a PolyData with Verts, appended raw, BigEndian, UInt32 headers */
        unsigned char app[512];
        size_t off[4], at = 0;
        off[0] = at;
        at += block(app + at, 4, 1, V, 3, 8);
        off[1] = at;
        at += block(app + at, 4, 1, h, 3, 8);
        off[2] = at;
        at += block(app + at, 4, 1, pts, 9, 4);
        off[3] = at;
        const int32_t conn[3] = {0, 1, 2};
        at += block(app + at, 4, 1, conn, 3, 4);
        int head = snprintf(
            file, sizeof file,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" "
            "byte_order=\"BigEndian\">\n<PolyData><Piece NumberOfPoints=\"3\" NumberOfVerts=\"3\">"
            "<PointData><DataArray type=\"Float64\" Name=\"V\" format=\"appended\" "
            "offset=\"%zu\"/><DataArray type=\"Float64\" Name=\"h\" format=\"appended\" "
            "offset=\"%zu\"/></PointData><Points><DataArray type=\"Float32\" "
            "NumberOfComponents=\"3\" format=\"appended\" offset=\"%zu\"/></Points>"
            "<Verts><DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" "
            "offset=\"%zu\"/></Verts></Piece></PolyData>\n"
            "<AppendedData encoding=\"raw\">\n _",
            off[0], off[1], off[2], off[3]);
        memcpy(file + head, app, at);
        static const char tail[] = "\n</AppendedData>\n</VTKFile>\n";
        memcpy(file + head + at, tail, sizeof tail - 1);
        spit(path_of("poly.vtp"), file, (size_t)head + at + sizeof tail - 1);
        CHECK_INT(pst_cloud_read_vtu(&r, path_of("poly.vtp"), err), PST_OK);
        if (*err && !r)
            fprintf(stderr, "  %s\n", err);
        CHECK(r && pst_cloud_dim(r) == 3 && pst_cloud_size(r) == 3);
        for (size_t i = 0; r && i < 3; ++i) {
            CHECK(pst_cloud_coord(r, 2)[i] == (double)pts[3 * i + 2]);
            CHECK(pst_cloud_volume(r)[i] == V[i] && pst_cloud_h_array(r)[i] == h[i]);
            CHECK_INT(pst_cloud_kinds(r)[i], PST_INTERIOR);
        }
        pst_cloud_destroy(r);
    }
}

/* One failing read: the status, *out NULL, the path and every `want` in the message. */
static void expect_fail(const char *path, int status, const char *want1, const char *want2)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *r = (pst_cloud *)&err; /* must be reset to NULL */
    int st = pst_cloud_read_vtu(&r, path, err);
    CHECK_INT(st, status);
    CHECK(r == NULL);
    int ok = strncmp(err, path, strlen(path)) == 0 && (!want1 || strstr(err, want1)) &&
             (!want2 || strstr(err, want2));
    CHECK(ok);
    if (!ok)
        fprintf(stderr, "  message: %s\n  wanted:  '%s' and '%s'\n", err, want1 ? want1 : "",
                want2 ? want2 : "");
    if (st == PST_OK)
        pst_cloud_destroy(r);
}

static void test_read_errors(void)
{
    char err[PST_ERRLEN] = "";
    expect_fail(path_of("no_such.vtu"), PST_EIO, "cannot open", NULL);
    /* structure */
    expect_fail(ascii_variant("e.vtu", "byte_order", "compressor=\"vtkLZ4DataCompressor\" bo"),
                PST_EINPUT, ":3:1: compressor \"vtkLZ4DataCompressor\" is not supported: only "
                            "vtkZLibDataCompressor (zlib) or none", NULL);
    expect_fail(ascii_variant("e.vtu", "byte_order", "compressor=\"vtkLZMADataCompressor\" bo"),
                PST_EINPUT, ":3:1: compressor \"vtkLZMADataCompressor\" is not supported", NULL);
    expect_fail(ascii_variant("e.vtu", "\"UnstructuredGrid\"", "\"ImageData\""), PST_EINPUT,
                ":3:1: unsupported dataset type \"ImageData\"", NULL);
    expect_fail(ascii_variant("e.vtu", "</Piece>", "</Piece><Piece NumberOfPoints=\"1\"/>"),
                PST_EINPUT, "more than one Piece", NULL);
    expect_fail(ascii_variant("e.vtu", "</PointData>", "</Pointdata>"), PST_EINPUT,
                ":18:9: malformed XML: mismatched tag: this end tag does not close <PointData> "
                "of 6:7", NULL);
    expect_fail(ascii_variant("e.vtu", "</VTKFile>\n", ""), PST_EINPUT,
                ":3:1: truncated file: <VTKFile> is not closed", NULL);
    expect_fail(ascii_variant("e.vtu", "format=\"ascii\">0.5", "format=\"ascii>0.5"),
                PST_EINPUT, ":7:71: malformed XML: not well-formed (invalid token) at '<'", NULL);
    expect_fail(ascii_variant("e.vtu", "type=\"Int32\"", "type=\"String\""), PST_EINPUT,
                ":9:9: array 'kind': unsupported type \"String\"", NULL);
    expect_fail(ascii_variant("e.vtu", "Name=\"h\"", "Name=\"hh\""), PST_EINPUT,
                "missing PointData array 'h'", NULL);
    expect_fail(ascii_variant("e.vtu", "Name=\"V\"", "Name=\"W\""), PST_EINPUT,
                "missing PointData array 'V'", NULL);
    expect_fail(ascii_variant("e.vtu", "Name=\"T\"", "Name=\"T-1\""), PST_EINPUT,
                ":14:9: PointData array 'T-1' cannot be a field", NULL);
    expect_fail(ascii_variant("e.vtu", "Name=\"T\"", "Name=\"nx\""), PST_EINPUT,
                "array 'nx' cannot be a field", NULL);
    expect_fail(ascii_variant("e.vtu", "Name=\"T\"", "Name=\"V\""), PST_EINPUT,
                "two PointData arrays are named 'V'", NULL);
    expect_fail(ascii_variant("e.vtu", "Name=\"T\"", "Name=\"T\" NumberOfComponents=\"2\""),
                PST_EINPUT, ":14:9: PointData array 'T' has 2 components: a field has 1, 3 (a "
                "vector) or 6 (a symmetric tensor)", NULL);
    /* a 3-component field is a vector: its fields must not clash, its z must be 0 in 2D */
    expect_fail(ascii_variant("e.vtu", "Name=\"normal\"", "Name=\"vel\""), PST_EINPUT,
                "array 'vel', point 2: component z = 7 must be 0 in a 2D cloud", NULL);
    {
        char t[sizeof ascii_vtu + 64];
        snprintf(t, sizeof t, "%s", ascii_vtu);
        replace_once(t, sizeof t, "Name=\"normal\"", "Name=\"q\"");
        replace_once(t, sizeof t, "Name=\"T\"", "Name=\"q_y\"");
        spit(path_of("e.vtu"), t, strlen(t));
        expect_fail(path_of("e.vtu"), PST_EINPUT,
                    ":14:9: two PointData arrays give the field 'q_y'", NULL);
    }
    expect_fail(ascii_variant("e.vtu", "Name=\"status\"", "Name=\"m\""), PST_EINPUT,
                "both 'm' and 'M'", NULL);
    expect_fail(ascii_variant("e.vtu", "0.5 0.25 1e-3", "0.5 0.25"), PST_EINPUT,
                ":7:9: array 'V' holds 2 values, expected 3", NULL);
    expect_fail(ascii_variant("e.vtu", "0.5 0.25 1e-3", "0.5 0.25 1e-3x"), PST_EINPUT,
                "array 'V': value 3: cannot parse '1e-3x'", NULL);
    /* values: named by array and point (the file's row) */
    expect_fail(ascii_variant("e.vtu", "0.5 0.25 1e-3", "0.5 nan 1e-3"), PST_EINPUT,
                "array 'V', point 1: value nan is not finite", NULL);
    expect_fail(ascii_variant("e.vtu", "0 1 0\n", "0 inf 0\n"), PST_EINPUT,
                "array 'Points', point 2, component 1: value inf is not finite", NULL);
    expect_fail(ascii_variant("e.vtu", "0.5 0.25 1e-3", "0.5 0.25 -1e-3"), PST_EINPUT,
                "array 'V', point 2: volume V = -0.001 must be > 0", NULL);
    expect_fail(ascii_variant("e.vtu", "0.5 0.5 0.5", "0.5 0 0.5"), PST_EINPUT,
                "array 'h', point 1: smoothing length h = 0 must be > 0", NULL);
    expect_fail(ascii_variant("e.vtu", "0 2 1<", "0 3 1<"), PST_EINPUT,
                "array 'kind', point 1: unknown kind 3", NULL);
    expect_fail(ascii_variant("e.vtu", "1 2 3 4 5 6", "1 2 3 4 -5 6"), PST_EINPUT,
                "array 'M', point 1: mobility -5 must be > 0", NULL);
    expect_fail(ascii_variant("e.vtu", "2 0 1<", "2 0 0<"), PST_EINPUT,
                "array 'id', point 2: id 0 also at point 1", "permutation");
    expect_fail(ascii_variant("e.vtu", "2 0 1<", "2 0 3<"), PST_EINPUT,
                "array 'id', point 2: id 3 is not in 0..2", NULL);
    expect_fail(ascii_variant("e.vtu", "0 0 0 1 0 0 0 1 0", "0 0 0 1 0 0 1 0 0"), PST_EINPUT,
                "array 'Points', point 2: duplicate particle: same coordinates as point 1",
                NULL);

    /* binary appended data: byte counts, offsets and truncation */
    pst_cloud *c = make_cloud(2, 1, 1);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("w.vtu"), NULL, err), PST_OK);
    pst_cloud_destroy(c);
    vtu_file v;
    CHECK(parse(&v, path_of("w.vtu")));
    if (v.ok) {
        size_t head = (size_t)(v.data - v.buf);
        const parsed_array *h = find(&v, "h");
        spit(path_of("trunc.vtu"), v.buf, head + h->offset + 20); /* cut inside h */
        expect_fail(path_of("trunc.vtu"), PST_EINPUT, "truncated file: no </AppendedData>",
                    NULL);
        /* cut inside the Points with the closing tags kept: the Points run past the block,
         * the Cells start beyond it (the Points are decoded first) */
        const parsed_array *pts = find(&v, "Points");
        size_t cut = head + pts->offset + 20, rest = strlen("\n  </AppendedData>\n</VTKFile>\n");
        unsigned char *b = malloc(cut + rest);
        memcpy(b, v.buf, cut);
        memcpy(b + cut, v.buf + v.len - rest, rest);
        spit(path_of("trunc.vtu"), b, cut + rest);
        free(b);
        char want[96];
        snprintf(want, sizeof want, "appended data offset %llu (array 'Points'): truncated",
                 (unsigned long long)pts->offset);
        expect_fail(path_of("trunc.vtu"), PST_EINPUT, want, "only 15 left");
        snprintf(want, sizeof want, "appended data offset %llu (array 'h')",
                 (unsigned long long)h->offset);
        /* a wrong byte count */
        v.buf[head + h->offset] ^= 8;
        spit(path_of("count.vtu"), v.buf, v.len);
        expect_fail(path_of("count.vtu"), PST_EINPUT, want, "byte count");
        v.buf[head + h->offset] ^= 8;
        /* a NaN in the data */
        memset(v.buf + head + h->offset + 8 + 8 * 5, 0xFF, 8);
        spit(path_of("nan.vtu"), v.buf, v.len);
        expect_fail(path_of("nan.vtu"), PST_EINPUT, "array 'h', point 5: value ",
                    "nan is not finite");
    }
    free(v.buf);
    /* invalid base64, and a block shorter than its header says */
    expect_fail(ascii_variant("e.vtu", "Name=\"V\" format=\"ascii\">0.5 0.25 1e-3",
                              "Name=\"V\" format=\"binary\">GAAAAA*AAAAAAA"),
                PST_EINPUT, ":7:9: array 'V': invalid base64 at character 7", NULL);
    expect_fail(ascii_variant("e.vtu", "Name=\"V\" format=\"ascii\">0.5 0.25 1e-3",
                              "Name=\"V\" format=\"binary\">GAAAAAAAAAAAAOA/"),
                PST_EINPUT, "array 'V': binary data holds 8 bytes after the header, the header "
                            "says 24", NULL);
}

/* A deterministic mutation fuzz: byte flips, bit flips, structural characters, truncations and
 * cut-out ranges of valid files. Every read returns PST_OK with a valid cloud or PST_EINPUT
 * naming the file; the sanitizer build catches any out-of-bounds access or leak. */
static void fuzz_file(const char *name, int rounds, uint64_t seed)
{
    size_t len = 0;
    unsigned char *orig = slurp(path_of(name), &len), *buf = malloc(len + 16);
    CHECK(orig && buf && len > 0);
    if (!orig || !buf || !len) {
        free(orig);
        free(buf);
        return;
    }
    /* where the XML ends (the interesting part): before '_' or the whole file */
    const unsigned char *us = memchr(orig, '_', len);
    size_t xml = us ? (size_t)(us - orig) + 1 : len;
    uint64_t s = seed;
#define RND() (s = s * 6364136223846793005ULL + 1442695040888963407ULL, s >> 33)
    static const char special[] = "<>/=\"' _0129-.\n&!?xe+";
    int ok = 0, input = 0, other = 0;
    const char *p = path_of("fuzz.vtu");
    for (int t = 0; t < rounds; ++t) {
        memcpy(buf, orig, len);
        size_t n = len;
        int nmut = 1 + (int)(RND() % 3);
        for (int m = 0; m < nmut && n > 0; ++m) {
            size_t at = RND() % 2 ? RND() % (xml < n ? xml : n) : RND() % n;
            switch (RND() % 6) {
            case 0:
                buf[at] = (unsigned char)RND();
                break;
            case 1:
                buf[at] ^= (unsigned char)(1u << (RND() % 8));
                break;
            case 2:
                buf[at] = (unsigned char)special[RND() % (sizeof special - 1)];
                break;
            case 3:
                n = at; /* truncate */
                break;
            case 4: { /* cut out a range */
                size_t k = 1 + RND() % 16;
                if (at + k > n)
                    k = n - at;
                memmove(buf + at, buf + at + k, n - at - k);
                n -= k;
                break;
            }
            default: /* a digit run: a bigger count or offset */
                buf[at] = (unsigned char)('0' + RND() % 10);
                break;
            }
        }
        spit(p, buf, n);
        char err[PST_ERRLEN] = "";
        pst_cloud *r = NULL;
        int st = pst_cloud_read_vtu(&r, p, err);
        if (st == PST_OK) {
            ++ok;
            other += r == NULL || pst_cloud_validate(r, NULL) != PST_OK;
        } else {
            ++input;
            other += st != PST_EINPUT || r != NULL || strncmp(err, p, strlen(p)) != 0;
        }
        pst_cloud_destroy(r);
    }
#undef RND
    CHECK_INT(other, 0);
    CHECK(input > rounds / 4); /* most mutations are caught */
    printf("  fuzz %s: %d mutations, %d read, %d refused\n", name, rounds, ok, input);
    free(orig);
    free(buf);
}

static void test_read_fuzz(void)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *c = make_cloud(2, 2, 1);
    uint8_t *status = make_status(c);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("fz_raw.vtu"), status, err), PST_OK);
    free(status);
    pst_cloud_destroy(c);
    fuzz_file("fz_raw.vtu", 3000, 1);
    ascii_variant("fz_ascii.vtu", NULL, NULL);
    fuzz_file("fz_ascii.vtu", 1500, 2);
    fuzz_file("b64.vtu", 1000, 3);
    fuzz_file("poly.vtp", 1000, 4);
    fuzz_file("fz_zraw.vtu", 1000, 5); /* compressed (test_read_zlib) */
    fuzz_file("fz_zb64.vtu", 1000, 6);
    fuzz_file("fz_zinline.vtu", 1000, 7);
}

/* ---- compressed input (vtkZLibDataCompressor): files made here with compress2 ------------- */

enum { ZM_RAW, ZM_B64, ZM_INLINE };

/* One array of a compressed test file: name NULL for the Points; values in host order. */
typedef struct {
    const char *name, *type;
    int ncomp, size;
    const void *vals;
} z_array;

/* A compressed test file, and where each array's compressed bytes start in the appended block
 * (ZM_RAW) and how long its header is. */
typedef struct {
    unsigned char buf[1 << 17];
    size_t len, data, off[8], hlen[8], zlen[8];
} z_file;

static void put_word(unsigned char *out, int hs, int big, uint64_t v)
{
    for (int b = 0; b < hs; ++b)
        out[big ? hs - 1 - b : b] = (unsigned char)(v >> (8 * b));
}

/* VTK's compressed form of count values of `size` bytes: the header [number of blocks, bs,
 * size of the last block (0: full), compressed size of each block] in hs-byte words, then one
 * zlib stream per block of bs uncompressed bytes. *hlen: the header's length; returns the
 * total length. */
static size_t zlib_blocks(unsigned char *out, int hs, int big, const void *vals, size_t count,
                          int size, size_t bs, size_t *hlen)
{
    size_t bytes = count * (size_t)size, nb = (bytes + bs - 1) / bs;
    unsigned char *plain = malloc((size_t)hs + bytes);
    block(plain, hs, big, vals, count, size); /* the values in the file's byte order */
    *hlen = (size_t)hs * (3 + nb);
    put_word(out, hs, big, nb);
    put_word(out + hs, hs, big, bs);
    put_word(out + 2 * hs, hs, big, bytes % bs);
    size_t at = *hlen;
    for (size_t b = 0; b < nb; ++b) {
        size_t u = bytes - b * bs < bs ? bytes - b * bs : bs;
        uLongf c = compressBound((uLong)u);
        CHECK_INT(compress2(out + at, &c, plain + hs + b * bs, (uLong)u, 9), Z_OK);
        put_word(out + (3 + b) * (size_t)hs, hs, big, c);
        at += c;
    }
    free(plain);
    return at;
}

/* A compressed .vtu of n points with arrays arr (the Points last) in `mode`, hs-byte headers,
 * blocks of bs bytes; into f (not written). */
static void zlib_vtu(z_file *f, int mode, int hs, int big, size_t n, const z_array *arr,
                     size_t na, size_t bs)
{
    static unsigned char z[1 << 15], app[1 << 16];
    static char text[1 << 16];
    char *xml = (char *)f->buf;
    size_t cap = sizeof f->buf, x = 0, a_len = 0;
    x += (size_t)snprintf(xml + x, cap - x,
                          "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" "
                          "version=\"1.0\" byte_order=\"%s\" header_type=\"%s\" "
                          "compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid>\n"
                          "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"0\">\n<PointData>\n",
                          big ? "BigEndian" : "LittleEndian", hs == 8 ? "UInt64" : "UInt32", n);
    for (size_t k = 0; k < na; ++k) {
        const z_array *a = &arr[k];
        size_t zl = zlib_blocks(z, hs, big, a->vals, n * (size_t)a->ncomp, a->size, bs,
                                &f->hlen[k]);
        f->zlen[k] = zl;
        f->off[k] = a_len;
        if (mode == ZM_RAW) {
            memcpy(app + a_len, z, zl);
            a_len += zl;
        } else { /* the header and the blocks: two base64 runs */
            b64_encode(z, f->hlen[k], text);
            b64_encode(z + f->hlen[k], zl - f->hlen[k], text + strlen(text));
        }
        if (mode == ZM_B64) {
            memcpy(app + a_len, text, strlen(text));
            a_len += strlen(text);
        }
        if (!a->name)
            x += (size_t)snprintf(xml + x, cap - x, "</PointData>\n<Points>\n");
        char nm[64] = "";
        if (a->name)
            snprintf(nm, sizeof nm, " Name=\"%s\"", a->name);
        if (mode == ZM_INLINE)
            x += (size_t)snprintf(xml + x, cap - x,
                                  "<DataArray type=\"%s\"%s NumberOfComponents=\"%d\" "
                                  "format=\"binary\">\n%s\n</DataArray>\n",
                                  a->type, nm, a->ncomp, text);
        else
            x += (size_t)snprintf(xml + x, cap - x,
                                  "<DataArray type=\"%s\"%s NumberOfComponents=\"%d\" "
                                  "format=\"appended\" offset=\"%zu\"/>\n",
                                  a->type, nm, a->ncomp, f->off[k]);
    }
    x += (size_t)snprintf(xml + x, cap - x, "</Points>\n</Piece>\n</UnstructuredGrid>\n");
    if (mode != ZM_INLINE) {
        x += (size_t)snprintf(xml + x, cap - x, "<AppendedData encoding=\"%s\">\n  _",
                              mode == ZM_RAW ? "raw" : "base64");
        f->data = x;
        memcpy(f->buf + x, app, a_len);
        x += a_len;
        x += (size_t)snprintf(xml + x, cap - x, "\n</AppendedData>\n");
    }
    x += (size_t)snprintf(xml + x, cap - x, "</VTKFile>\n");
    f->len = x;
}

enum { ZN = 40 }; /* points: the Points (960 bytes) span 4 blocks of 256, the last short */

/* The arrays of the compressed files: 3D (or 2D: z = 0 and the out-of-plane components 0,
 * except where `bad_z`) positions, V, h, a Float32 vector vel and a symmetric tensor S. */
typedef struct {
    double pts[3 * ZN], V[ZN], h[ZN], S[6 * ZN];
    float vel[3 * ZN];
} z_values;

static void z_fill(z_values *v, int dim)
{
    for (size_t k = 0; k < ZN; ++k) {
        v->pts[3 * k] = (double)(k % 4) + 0.125 * sin((double)k);
        v->pts[3 * k + 1] = (double)(k / 4 % 5) - 1e-3 * (double)k;
        v->pts[3 * k + 2] = dim == 3 ? (double)(k / 20) + 1.0 / 3 : 0.0;
        v->V[k] = 1.0 / (double)(k + 2);
        v->h[k] = 0.5 + (double)k / 1024;
        for (int d = 0; d < 3; ++d)
            v->vel[3 * k + (size_t)d] = d < dim ? (float)k * 0.25f - (float)d : 0.0f;
        for (int j = 0; j < 6; ++j) {
            int in_plane = j == 0 || j == 1 || j == 3;
            v->S[6 * k + (size_t)j] = dim == 3 || in_plane ? exp(-(double)k / 9) * (j + 1) : 0;
        }
    }
}

static size_t z_arrays(z_array *arr, const z_values *v)
{
    const z_array list[5] = {{"V", "Float64", 1, 8, v->V},     {"h", "Float64", 1, 8, v->h},
                             {"vel", "Float32", 3, 4, v->vel}, {"S", "Float64", 6, 8, v->S},
                             {NULL, "Float64", 3, 8, v->pts}};
    memcpy(arr, list, sizeof list);
    return 5;
}

/* The cloud read from a compressed file against the values, exactly. */
static void z_check(pst_cloud *r, const z_values *v, int dim)
{
    static const char *const vn[3] = {"vel_x", "vel_y", "vel_z"},
                             *const sn[6] = {"S_xx", "S_yy", "S_zz", "S_xy", "S_yz", "S_xz"};
    CHECK(r != NULL);
    if (!r)
        return;
    CHECK_INT(pst_cloud_size(r), ZN);
    CHECK_INT(pst_cloud_dim(r), dim);
    CHECK_INT(pst_cloud_nfields(r), dim == 3 ? 9 : 5);
    size_t bad = 0;
    for (size_t k = 0; k < ZN; ++k) {
        for (int d = 0; d < dim; ++d)
            bad += pst_cloud_coord(r, d)[k] != v->pts[3 * k + (size_t)d];
        bad += pst_cloud_volume(r)[k] != v->V[k] || pst_cloud_h_array(r)[k] != v->h[k];
        for (int d = 0; d < 3; ++d) {
            const double *f = pst_cloud_field_by_name(r, vn[d]);
            bad += d < dim ? !f || f[k] != (double)v->vel[3 * k + (size_t)d] : f != NULL;
        }
        for (int j = 0; j < 6; ++j) {
            const double *f = pst_cloud_field_by_name(r, sn[j]);
            int kept = dim == 3 || j == 0 || j == 1 || j == 3;
            bad += kept ? !f || f[k] != v->S[6 * k + (size_t)j] : f != NULL;
        }
    }
    CHECK_INT(bad, 0);
    /* the fields in file order, each split in component order */
    CHECK(!strcmp(pst_cloud_field_name(r, 0), "vel_x"));
    CHECK(!strcmp(pst_cloud_field_name(r, dim), "S_xx"));
    CHECK(!strcmp(pst_cloud_field_name(r, dim + 2), dim == 3 ? "S_zz" : "S_xy"));
}

static void test_read_zlib(void)
{
    char err[PST_ERRLEN] = "";
    static z_file f;
    z_values v;
    z_array arr[5];
    size_t na = z_arrays(arr, &v);
    static const char *const mode_name[3] = {"appended raw", "appended base64", "binary"};
    for (int dim = 2; dim <= 3; ++dim) {
        z_fill(&v, dim);
        for (int mode = ZM_RAW; mode <= ZM_INLINE; ++mode)
            for (int hs = 4; hs <= 8; hs += 4) {
                int big = (mode + hs / 4 + dim) % 2; /* both byte orders in every mode */
                zlib_vtu(&f, mode, hs, big, ZN, arr, na, 256);
                spit(path_of("z.vtu"), f.buf, f.len);
                pst_cloud *r = NULL;
                int st = pst_cloud_read_vtu(&r, path_of("z.vtu"), err);
                CHECK_INT(st, PST_OK);
                if (st != PST_OK)
                    fprintf(stderr, "  %dD %s, UInt%d: %s\n", dim, mode_name[mode], 8 * hs, err);
                z_check(r, &v, dim);
                pst_cloud_destroy(r);
            }
    }
    /* one block per array, and blocks of exactly the array's size (last-block size 0) */
    z_fill(&v, 3);
    for (size_t bs = 1 << 14; bs >= 320; bs = 320) {
        zlib_vtu(&f, ZM_RAW, 8, 0, ZN, arr, na, bs);
        spit(path_of("z.vtu"), f.buf, f.len);
        pst_cloud *r = NULL;
        CHECK_INT(pst_cloud_read_vtu(&r, path_of("z.vtu"), err), PST_OK);
        z_check(r, &v, 3);
        pst_cloud_destroy(r);
        if (bs == 320)
            break;
    }

    /* 2D: a vector or tensor component out of the plane must be 0 */
    z_fill(&v, 2);
    v.vel[3 * 7 + 2] = 0.5f;
    zlib_vtu(&f, ZM_INLINE, 4, 0, ZN, arr, na, 256);
    spit(path_of("z.vtu"), f.buf, f.len);
    expect_fail(path_of("z.vtu"), PST_EINPUT,
                "array 'vel', point 7: component z = 0.5 must be 0 in a 2D cloud", NULL);
    v.vel[3 * 7 + 2] = 0;
    v.S[6 * 3 + 4] = -2;
    zlib_vtu(&f, ZM_RAW, 4, 0, ZN, arr, na, 256);
    spit(path_of("z.vtu"), f.buf, f.len);
    expect_fail(path_of("z.vtu"), PST_EINPUT,
                "array 'S', point 3: component yz = -2 must be 0 in a 2D cloud", NULL);

    /* damaged files: each error names the array and where its data is */
    z_fill(&v, 3);
    zlib_vtu(&f, ZM_RAW, 8, 0, ZN, arr, na, 256);
    const size_t P = 4; /* the Points: 4 blocks, the last 192 bytes */
    char want[160];
    static unsigned char copy[sizeof f.buf];
    /* a truncated block: the file cut inside the Points' last block, the end tags kept */
    {
        static const char tail[] = "\n</AppendedData>\n</VTKFile>\n";
        size_t cut = f.data + f.off[P] + f.zlen[P] - 10;
        memcpy(copy, f.buf, cut);
        memcpy(copy + cut, tail, sizeof tail - 1);
        spit(path_of("z.vtu"), copy, cut + sizeof tail - 1);
        snprintf(want, sizeof want, "appended data offset %zu (array 'Points'): compressed "
                 "data: block 4 of 4: truncated", f.off[P]);
        expect_fail(path_of("z.vtu"), PST_EINPUT, want, "compressed bytes, at most");
    }
    /* a wrong uncompressed size: the last block said to be 200 bytes instead of 192 */
    memcpy(copy, f.buf, f.len);
    put_word(copy + f.data + f.off[P] + 16, 8, 0, 200);
    spit(path_of("z.vtu"), copy, f.len);
    expect_fail(path_of("z.vtu"), PST_EINPUT,
                "(array 'Points'): compressed data: uncompressed size 968 (4 blocks of 256 "
                "bytes, the last 200), expected 960 (40 points x 3 components x 8 bytes)", NULL);
    /* an absurd block count is refused before anything is allocated */
    memcpy(copy, f.buf, f.len);
    put_word(copy + f.data + f.off[0], 8, 0, (uint64_t)1 << 60);
    spit(path_of("z.vtu"), copy, f.len);
    expect_fail(path_of("z.vtu"), PST_EINPUT, "(array 'V'): compressed data: the header "
                "declares 1152921504606846976 blocks, more than", NULL);
    /* a corrupt zlib stream: the first byte of V's second block */
    memcpy(copy, f.buf, f.len);
    uint64_t c0 = f.buf[f.data + f.off[0] + 24];
    copy[f.data + f.off[0] + f.hlen[0] + c0] ^= 0x55;
    spit(path_of("z.vtu"), copy, f.len);
    snprintf(want, sizeof want, "appended data offset %zu (array 'V'): compressed data: block 2 "
             "of 2: corrupt zlib stream (data error)", f.off[0]);
    expect_fail(path_of("z.vtu"), PST_EINPUT, want, NULL);
    /* a block that inflates to fewer bytes than the header says: V's blocks swapped in size */
    memcpy(copy, f.buf, f.len);
    put_word(copy + f.data + f.off[0] + 8, 8, 0, 64);  /* block size */
    put_word(copy + f.data + f.off[0] + 16, 8, 0, 0);  /* the last: full */
    put_word(copy + f.data + f.off[0], 8, 0, 5);       /* 5 x 64 = 320 */
    spit(path_of("z.vtu"), copy, f.len);
    expect_fail(path_of("z.vtu"), PST_EINPUT, "(array 'V'): compressed data: block 1 of 5",
                NULL);
    /* inline: the same errors at the array's LINE:COLUMN */
    zlib_vtu(&f, ZM_INLINE, 4, 1, ZN, arr, na, 256);
    char *p = strstr((char *)f.buf, "Name=\"h\"");
    CHECK(p != NULL);
    if (p) {
        char *data = strchr(p, '\n') + 1;
        data[0] = data[0] == 'A' ? 'B' : 'A'; /* the block count */
        spit(path_of("z.vtu"), f.buf, f.len);
        expect_fail(path_of("z.vtu"), PST_EINPUT, ":9:1: array 'h': compressed data: the header "
                    "declares 67108866 blocks, more than the 128 bytes left can describe", NULL);
    }
    /* an unknown compressor is named */
    zlib_vtu(&f, ZM_RAW, 8, 0, ZN, arr, na, 256);
    p = strstr((char *)f.buf, "vtkZLibDataCompressor");
    memcpy(p, "vtkLZ4DataCompressor\" ", 22);
    spit(path_of("z.vtu"), f.buf, f.len);
    expect_fail(path_of("z.vtu"), PST_EINPUT, ":2:1: compressor \"vtkLZ4DataCompressor\" is not "
                "supported: only vtkZLibDataCompressor", NULL);

    /* inputs of the mutation fuzz (test_read_fuzz) */
    static const char *const fz[3] = {"fz_zraw.vtu", "fz_zb64.vtu", "fz_zinline.vtu"};
    for (int mode = ZM_RAW; mode <= ZM_INLINE; ++mode) {
        zlib_vtu(&f, mode, 4 + 4 * (mode == ZM_B64), mode == ZM_INLINE, ZN, arr, na, 256);
        spit(path_of(fz[mode]), f.buf, f.len);
    }
}

/* The ascii file with nf more field arrays f0, f1, ... (the last named `last` when given)
 * after T, field k holding k, k + 1, k + 2; written as `name`. */
static const char *wide_vtu(const char *name, size_t nf, const char *last)
{
    const char *at = strstr(ascii_vtu, "      </PointData>");
    size_t cap = sizeof ascii_vtu + nf * 100, n = 0;
    char *t = malloc(cap);
    n += (size_t)snprintf(t, cap, "%.*s", (int)(at - ascii_vtu), ascii_vtu);
    for (size_t k = 0; k < nf; ++k) {
        char nm[32];
        snprintf(nm, sizeof nm, "f%zu", k);
        n += (size_t)snprintf(t + n, cap - n, "        <DataArray type=\"Float64\" Name=\"%s\" "
                              "format=\"ascii\">%zu %zu %zu</DataArray>\n",
                              last && k + 1 == nf ? last : nm, k, k + 1, k + 2);
    }
    n += (size_t)snprintf(t + n, cap - n, "%s", at);
    spit(path_of(name), t, n);
    free(t);
    return path_of(name);
}

/* Many arrays (issue 16): the pairwise name check and the per-field set-up took over a
 * minute for 20 000 arrays. Now at most PST_MAX_FIELDS fields, the cap and the array named. */
static void test_many_arrays(void)
{
    expect_fail(wide_vtu("w.vtu", 20000, NULL), PST_EINPUT,
                "PointData array 'f4095': more than the 4096 fields a cloud file may have", NULL);
    expect_fail(wide_vtu("w.vtu", PST_MAX_FIELDS, NULL), PST_EINPUT, "'f4095': more than", NULL);
    expect_fail(wide_vtu("w.vtu", PST_MAX_FIELDS - 1, "T"), PST_EINPUT,
                "two PointData arrays are named 'T'", NULL);
    char err[PST_ERRLEN] = "";
    pst_cloud *r = NULL;
    CHECK_INT(pst_cloud_read_vtu(&r, wide_vtu("w.vtu", PST_MAX_FIELDS - 1, NULL), err), PST_OK);
    if (!r)
        return;
    CHECK_INT(pst_cloud_nfields(r), PST_MAX_FIELDS);
    CHECK(strcmp(pst_cloud_field_name(r, 0), "T") == 0);
    CHECK(strcmp(pst_cloud_field_name(r, 4001), "f4000") == 0);
    const double *f = pst_cloud_field_by_name(r, "f4000"), *T = pst_cloud_field(r, 0);
    int ok = f != NULL;
    for (size_t i = 0; ok && i < 3; ++i) /* T tells the file row: -1.5, 2.5, 0.125 */
        ok = f[i] == 4000.0 + (T[i] == -1.5 ? 0 : T[i] == 2.5 ? 1 : 2);
    CHECK(ok);
    pst_cloud_destroy(r);
}

int main(void)
{
    if (test_scratch_dir(dir, sizeof dir, "pst_test_vtu") != 0)
        return 1;
    test_layouts();
    test_exact_bytes();
    test_failures();
    test_read_roundtrip();
    test_read_formats();
    test_read_errors();
    test_read_zlib();
    test_many_arrays();
    test_read_fuzz();
    test_remove_dir(dir);
    return check_summary("test_vtu");
}
