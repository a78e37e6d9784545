/* VTU output: the files are re-read by a small parser of the appended raw format, which checks
 * the XML header, every array's type, component count, offset and UInt64 byte count, that the
 * arrays tile the appended block exactly, and every value bit for bit against the cloud in
 * input order. Also: the file does not depend on the cloud's storage order, and failed writes
 * (no such directory, a write cut short, bad ids, a field named like a file array) leave no
 * file behind. tests/vtu_roundtrip.py reads files with VTK's own reader. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp, setrlimit, opendir */

#include "check.h"
#include "pstencil.h"

#include <dirent.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

static char dir[64];

static const char *path_of(const char *name)
{
    static char buf[256];
    snprintf(buf, sizeof buf, "%s/%s", dir, name);
    return buf;
}

/* Temporary files the writer might have left behind. */
static int leftovers(void)
{
    int k = 0;
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));)
        k += strstr(e->d_name, ".tmp.") != NULL;
    if (d)
        closedir(d);
    return k;
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
    pst_cloud_set_mobility(c, mob);
    pst_cloud_add_field(c, "u", &u);
    pst_cloud_add_field(c, "rhs_2", &rhs);
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
    CHECK_INT(pst_cloud_permute(c, perm), PST_OK);
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
    CHECK_INT(pst_cloud_permute(c, perm), PST_OK);
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
    CHECK_INT(pst_cloud_create(&c, 2, 1), PST_OK);
    pst_cloud_coord(c, 0)[0] = 1.5;
    pst_cloud_coord(c, 1)[0] = -2.0;
    pst_cloud_set_h_uniform(c, 0.25);
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
    CHECK_INT(pst_cloud_create(&c, 3, 0), PST_OK);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("empty.vtu"), NULL, err), PST_OK);
    CHECK(parse(&v, path_of("empty.vtu")));
    CHECK_INT(v.npoints, 0);
    CHECK_INT(v.na, 9);
    CHECK_INT(v.a[v.na ? v.na - 1 : 0].offset, 8 * 8);
    free(v.buf);
    pst_cloud_destroy(c);
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
    FILE *f = fopen(path_of("keep.vtu"), "w");
    fputs(old, f);
    fclose(f);
    struct rlimit saved, small;
    getrlimit(RLIMIT_FSIZE, &saved);
    small = saved;
    small.rlim_cur = 2048; /* the header fits, the data does not */
    void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
    CHECK(setrlimit(RLIMIT_FSIZE, &small) == 0);
    int st = pst_cloud_write_vtu(c, path_of("keep.vtu"), status, err);
    setrlimit(RLIMIT_FSIZE, &saved);
    signal(SIGXFSZ, prev);
    CHECK_INT(st, PST_EIO);
    CHECK(strstr(err, "keep.vtu") != NULL);
    char buf[64] = "";
    f = fopen(path_of("keep.vtu"), "r");
    size_t got = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
    if (f)
        fclose(f);
    CHECK(got == strlen(old) && !strcmp(buf, old));
    CHECK_INT(leftovers(), 0);

    /* rename onto a directory fails after the write: the temporary file is removed */
    mkdir(path_of("a_dir"), 0755);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("a_dir"), status, err), PST_EIO);
    CHECK(strstr(err, "rename") != NULL);
    CHECK_INT(leftovers(), 0);
    rmdir(path_of("a_dir"));

    /* a field named like one of the file's arrays */
    double *x;
    CHECK_INT(pst_cloud_add_field(c, "status", &x), PST_OK);
    CHECK_INT(pst_cloud_write_vtu(c, path_of("clash.vtu"), status, err), PST_EINVAL);
    CHECK(strstr(err, "clash.vtu") && strstr(err, "'status'"));
    CHECK(stat(path_of("clash.vtu"), &sb) != 0);
    /* ... which is fine when the file has no status array */
    CHECK_INT(pst_cloud_write_vtu(c, path_of("clash.vtu"), NULL, err), PST_OK);
    CHECK(unlink(path_of("clash.vtu")) == 0);
    CHECK_INT(pst_cloud_add_field(c, "normal", &x), PST_OK);
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

static void cleanup(void)
{
    DIR *d = opendir(dir);
    char p[512];
    for (struct dirent *e; d && (e = readdir(d));) {
        if (e->d_name[0] == '.')
            continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        unlink(p);
    }
    if (d)
        closedir(d);
    rmdir(dir);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/pst_test_vtu_XXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_layouts();
    test_exact_bytes();
    test_failures();
    cleanup();
    return check_summary("test_vtu");
}
