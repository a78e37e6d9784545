/* CSV input and output: the tokenizer (quoting, empty cells, CRLF, a byte-order mark, the
 * trimming and blank-line flags, the caps, numbers, the file:line:column of every error) and
 * the table with its typed cells; then clouds: exact round trips in 2D and 3D with every
 * optional column, the messages of each kind of bad input, and the atomic-replace guarantees
 * of the writer. */
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

static char dir[64];

static const char *path_of(const char *name)
{
    return test_path_in(dir, name);
}

static void write_text(const char *name, const char *text)
{
    CHECK_INT(test_write_text(path_of(name), text), 0);
}

static int bits_equal(const double *a, const double *b, size_t n)
{
    return !memcmp(a, b, n * sizeof *a);
}

/* Temporary files the writer might have left behind. */
static int leftovers(void)
{
    return test_count_temporaries(dir);
}

/* ---- the tokenizer and the table ------------------------------------------------------ */

/* Parse `text` as a table; expect `status` and, on failure, `needle` in the message. */
static int parse_expect(pst_csv_table *t, const char *text, int flags, int status,
                        const char *needle)
{
    char err[PST_ERRLEN] = "";
    int st = pst_csv_parse_table(t, text, "t.csv", flags, err);
    CHECK_INT(st, status);
    if (needle && !strstr(err, needle)) {
        CHECK(!"message");
        fprintf(stderr, "  message was: %s (expected %s)\n", err, needle);
    }
    return st == PST_OK;
}

static const char *tcell(const pst_csv_table *t, size_t r, int c)
{
    return t->cell[r * (size_t)t->ncols + (size_t)c];
}

static void test_tokenizer_quoting(void)
{
    pst_csv_table t;
    /* quoted commas, doubled quotes, a quoted newline, empty cells, CRLF, no final newline */
    if (parse_expect(&t, "a,b,c\r\n\"x, y\",\"say \"\"hi\"\"\",\"two\nlines\"\r\n,,\r\n\"\",q,",
                     0, PST_OK, NULL)) {
        CHECK_INT(t.nrows, 3);
        CHECK_INT(t.ncols, 3);
        CHECK(!strcmp(tcell(&t, 0, 2), "c"));
        CHECK(!strcmp(tcell(&t, 1, 0), "x, y") && !strcmp(tcell(&t, 1, 1), "say \"hi\"") &&
              !strcmp(tcell(&t, 1, 2), "two\nlines"));
        CHECK(!strcmp(tcell(&t, 2, 0), "") && !strcmp(tcell(&t, 2, 2), ""));
        CHECK(!strcmp(tcell(&t, 3, 0), "") && !strcmp(tcell(&t, 3, 1), "q") &&
              !strcmp(tcell(&t, 3, 2), ""));
    }
    pst_csv_table_free(&t);
    /* a quote inside an unquoted cell is text; a quoted CRLF is kept */
    if (parse_expect(&t, "a,b\nx\"y,\"1\r\n2\"\n", 0, PST_OK, NULL))
        CHECK(!strcmp(tcell(&t, 1, 0), "x\"y") && !strcmp(tcell(&t, 1, 1), "1\r\n2"));
    pst_csv_table_free(&t);
    /* without flags, spaces are kept (a quote after one is text) and a blank line is a
     * record of one empty cell */
    if (parse_expect(&t, "\xEF\xBB\xBF" "a,b\n 1 , \"2\" \n", 0, PST_OK, NULL)) {
        CHECK(!strcmp(tcell(&t, 0, 0), "a")); /* the byte-order mark is skipped */
        CHECK(!strcmp(tcell(&t, 1, 0), " 1 ") && !strcmp(tcell(&t, 1, 1), " \"2\" "));
    }
    pst_csv_table_free(&t);
    parse_expect(&t, "a\n1\n\n2\n", 0, PST_OK, NULL);
    CHECK(t.nrows == 3 && !strcmp(tcell(&t, 2, 0), ""));
    pst_csv_table_free(&t);
    /* with the flags: trimmed cells (outside the quotes), blank lines skipped */
    if (parse_expect(&t, "a , b\n\n \t\n 1 , \" 2 \" \r\n", PST_CSV_TRIM | PST_CSV_SKIP_BLANK,
                     PST_OK, NULL)) {
        CHECK(t.nrows == 1 && !strcmp(tcell(&t, 0, 0), "a") && !strcmp(tcell(&t, 0, 1), "b"));
        CHECK(!strcmp(tcell(&t, 1, 0), "1") && !strcmp(tcell(&t, 1, 1), " 2 "));
    }
    pst_csv_table_free(&t);
}

static void test_tokenizer_errors(void)
{
    pst_csv_table t;
    parse_expect(&t, "", 0, PST_EINPUT, "t.csv:1:1: empty file: no header line");
    parse_expect(&t, "\n \n", PST_CSV_SKIP_BLANK, PST_EINPUT, "t.csv:1:1: empty file");
    parse_expect(&t, "a,b\n1,\"open\n2,3\n", 0, PST_EINPUT, "t.csv:2:2: unterminated quoted");
    parse_expect(&t, "a,b\n\"1\"x,2\n", 0, PST_EINPUT, "t.csv:2:1: text after a quoted cell");
    parse_expect(&t, "a,b,c\n1,2,3\n\"x\ny\"\n", 0, PST_EINPUT,
                 "t.csv:3:2: expected 3 columns, found 1");
    parse_expect(&t, "a,b\n1,2,3\n", 0, PST_EINPUT, "t.csv:2:3: expected 2 columns, found 3");
    /* blank lines count for the line numbers */
    parse_expect(&t, "a,b\n\n1,2\n\n1\n", PST_CSV_SKIP_BLANK, PST_EINPUT, "t.csv:5:2:");
    CHECK(t.cell == NULL && t.nrows == 0); /* empty on failure */
    /* a NUL byte is refused, not a silent end of the line */
    FILE *f = fopen(path_of("nul.csv"), "wb");
    fwrite("a,b\n1,2\0x\n3,4\n", 1, 14, f);
    fclose(f);
    char err[PST_ERRLEN] = "";
    CHECK_INT(pst_csv_read_table(&t, path_of("nul.csv"), 0, err), PST_EINPUT);
    CHECK(strstr(err, "nul.csv:2: a NUL byte") != NULL);
}

static void test_tokenizer_caps(void)
{
    pst_csv_table t;
    /* a record over PST_CSV_MAX_RECORD bytes: refused while it is read */
    size_t big = (size_t)PST_CSV_MAX_RECORD + 100;
    char *text = malloc(big + 16);
    memcpy(text, "a\n", 2);
    memset(text + 2, '7', big);
    strcpy(text + 2 + big, "\n");
    parse_expect(&t, text, 0, PST_EINPUT, "t.csv:2:1: a record longer than");
    /* more than PST_CSV_MAX_CELLS cells */
    size_t nc = (size_t)PST_CSV_MAX_CELLS + 1;
    for (size_t k = 0; k < nc; ++k)
        memcpy(text + 2 * k, "c,", 2);
    text[2 * nc - 1] = '\n';
    text[2 * nc] = '\0';
    parse_expect(&t, text, 0, PST_EINPUT, "t.csv:1:65537: more than 65536 cells");
    free(text);
    /* more than PST_CSV_MAX_ROWS data rows in a table */
    size_t nr = (size_t)PST_CSV_MAX_ROWS + 1;
    text = malloc(2 * nr + 8);
    memcpy(text, "x\n", 2);
    for (size_t r = 1; r <= nr; ++r)
        memcpy(text + 2 * r, "1\n", 2);
    text[2 * nr + 2] = '\0';
    char line[64];
    snprintf(line, sizeof line, "t.csv:%zu:1: more than %d data rows", nr + 1, PST_CSV_MAX_ROWS);
    parse_expect(&t, text, 0, PST_EINPUT, line);
    free(text);
    /* a table's rows must have its header's cell count */
    char err[PST_ERRLEN];
    const char *cells[3] = {"a", "b", "c"};
    CHECK_INT(pst_csv_table_add(&t, 2, cells, err), PST_OK);
    CHECK_INT(pst_csv_table_add(&t, 3, cells, err), PST_EINVAL);
    CHECK_INT(pst_csv_table_add(&t, 2, cells + 1, err), PST_OK);
    CHECK(t.nrows == 1 && !strcmp(tcell(&t, 1, 1), "c") && isnan(t.num[2]));
    pst_csv_table_free(&t);
}

static void test_numbers(void)
{
    double v = -1;
    CHECK_INT(pst_csv_parse_number("1.5e-3", &v), PST_CSV_NUMBER);
    CHECK(v == 1.5e-3);
    CHECK_INT(pst_csv_parse_number(" -2", &v), PST_CSV_NUMBER);
    CHECK(v == -2);
    v = 7;
    CHECK_INT(pst_csv_parse_number("", &v), PST_CSV_EMPTY);
    CHECK_INT(pst_csv_parse_number("abc", &v), PST_CSV_NOT_A_NUMBER);
    CHECK_INT(pst_csv_parse_number("2 ", &v), PST_CSV_NOT_A_NUMBER);
    CHECK_INT(pst_csv_parse_number("1.5x", &v), PST_CSV_NOT_A_NUMBER);
    CHECK_INT(pst_csv_parse_number("1e999", &v), PST_CSV_NOT_FINITE);
    CHECK_INT(pst_csv_parse_number("nan", &v), PST_CSV_NOT_FINITE);
    CHECK_INT(pst_csv_parse_number("-inf", &v), PST_CSV_NOT_FINITE);
    CHECK(v == 7); /* untouched */

    /* the table's typed cells: parsed once, NAN for anything that is not a finite number */
    pst_csv_table t;
    if (parse_expect(&t, "k,x\na,0.25\nb,\nc,inf\nd,x1\n", 0, PST_OK, NULL)) {
        CHECK(isnan(t.num[0]) && isnan(t.num[1])); /* the header */
        CHECK(isnan(t.num[2]) && t.num[3] == 0.25);
        CHECK(isnan(t.num[5]) && isnan(t.num[7]) && isnan(t.num[9]));
        CHECK_INT(pst_csv_table_column(&t, "x", t.ncols), 1);
        CHECK_INT(pst_csv_table_column(&t, "x", 1), -1);
    }
    pst_csv_table_free(&t);

    /* the streaming reader: records one by one, each with its first line; cell messages */
    char err[PST_ERRLEN] = "";
    pst_csv_reader *r;
    CHECK_INT(pst_csv_open_text(&r, "a,b\n1,\"x\ny\"\n2,\n3,1e999\n4,q\n", "s.csv", 0, err),
              PST_OK);
    if (!r)
        return;
    CHECK(pst_csv_ncols(r) == 2 && !strcmp(pst_csv_name(r, 1), "b"));
    int got = 0;
    CHECK_INT(pst_csv_next(r, &got, err), PST_OK);
    CHECK(got && pst_csv_line(r) == 2 && !strcmp(pst_csv_cell(r, 1), "x\ny"));
    CHECK_INT(pst_csv_number(r, 0, &v, err), PST_OK);
    CHECK(v == 1);
    CHECK_INT(pst_csv_number(r, 1, &v, err), PST_EINPUT);
    CHECK(!strcmp(err, "s.csv:2:2: column b: cannot parse 'x\ny' as a number"));
    CHECK_INT(pst_csv_next(r, &got, err), PST_OK);
    CHECK(got && pst_csv_line(r) == 4);
    CHECK_INT(pst_csv_number(r, 1, &v, err), PST_EINPUT);
    CHECK(!strcmp(err, "s.csv:4:2: column b: missing value"));
    CHECK_INT(pst_csv_next(r, &got, err), PST_OK);
    CHECK_INT(pst_csv_number(r, 1, &v, err), PST_EINPUT);
    CHECK(!strcmp(err, "s.csv:5:2: column b: value '1e999' is not finite"));
    CHECK_INT(pst_csv_cell_error(r, 0, PST_EINVAL, err, "odd %d", 3), PST_EINVAL);
    CHECK(!strcmp(err, "s.csv:5:1: column a: odd 3"));
    CHECK_INT(pst_csv_next(r, &got, err), PST_OK);
    CHECK_INT(pst_csv_next(r, &got, err), PST_OK);
    CHECK(got == 0);
    pst_csv_close(r);
}

/* ---- clouds ------------------------------------------------------------------------------ */

/* A jittered cell-centred cloud with every kind, per-particle h, mobility and two fields,
 * permuted so that its order differs from the input order. Hard values on purpose: -0,
 * subnormals, 1/3, huge and tiny magnitudes. */
static pst_cloud *make_cloud(int dim, int mob)
{
    pst_lattice_opts o;
    pst_lattice_defaults(&o);
    o.dim = dim;
    o.s0 = 0.25;
    o.jitter = 0.3;
    o.seed = 99;
    pst_cloud *c;
    if (pst_cloud_cell_centred(&c, &o, NULL) != PST_OK)
        return NULL;
    size_t n = pst_cloud_size(c);
    double *h = pst_cloud_h_per_particle(c), *u, *rhs;
    pst_cloud_set_mobility(c, mob, NULL);
    pst_cloud_add_field(c, "u", &u, NULL);
    pst_cloud_add_field(c, "rhs_2", &rhs, NULL);
    for (size_t i = 0; i < n; ++i) {
        h[i] = 0.3 + (double)i / 3;
        u[i] = i % 4 == 0 ? -0.0 : i % 4 == 1 ? 4.9e-320 : i % 4 == 2 ? 1e300 : -1.0 / 7;
        rhs[i] = sin((double)i) * 1e-200;
        for (int m = 0; m < mob; ++m)
            pst_cloud_mobility(c, m)[i] = 1 + (double)(i + (size_t)m) / 9;
    }
    pst_cloud_kinds(c)[n - 1] = PST_NEUMANN;
    pst_cloud_kinds(c)[n - 2] = PST_NEUMANN;
    uint32_t *perm = malloc(n * sizeof *perm);
    for (size_t i = 0; i < n; ++i)
        perm[i] = (uint32_t)(n - 1 - i);
    pst_cloud_permute(c, perm, NULL);
    free(perm);
    return c;
}

/* The read cloud, in input order, against the written one through its ids. */
static int same_in_input_order(pst_cloud *w, pst_cloud *r)
{
    size_t n = pst_cloud_size(w);
    if (pst_cloud_size(r) != n || pst_cloud_dim(r) != pst_cloud_dim(w) ||
        pst_cloud_nfields(r) != pst_cloud_nfields(w) ||
        pst_cloud_mobility_ncomp(r) != pst_cloud_mobility_ncomp(w) ||
        pst_cloud_h_is_uniform(r) != pst_cloud_h_is_uniform(w))
        return 0;
    double *tmp = malloc(n * sizeof *tmp);
    int ok = 1;
#define SAME(wa, ra)                                                                           \
    do {                                                                                       \
        pst_cloud_to_input_order(w, wa, tmp);                                                  \
        ok = ok && bits_equal(tmp, ra, n);                                                     \
    } while (0)
    for (int d = 0; d < pst_cloud_dim(w); ++d) {
        SAME(pst_cloud_coord(w, d), pst_cloud_coord(r, d));
        SAME(pst_cloud_normal(w, d), pst_cloud_normal(r, d));
    }
    SAME(pst_cloud_volume(w), pst_cloud_volume(r));
    if (!pst_cloud_h_is_uniform(w))
        SAME(pst_cloud_h_array(w), pst_cloud_h_array(r));
    for (int m = 0; m < pst_cloud_mobility_ncomp(w); ++m)
        SAME(pst_cloud_mobility(w, m), pst_cloud_mobility(r, m));
    for (size_t k = 0; k < pst_cloud_nfields(w); ++k) {
        ok = ok && !strcmp(pst_cloud_field_name(w, k), pst_cloud_field_name(r, k));
        SAME(pst_cloud_field(w, k), pst_cloud_field(r, k));
    }
#undef SAME
    for (size_t i = 0; i < n; ++i) {
        int64_t id = pst_cloud_ids(w)[i];
        ok = ok && pst_cloud_kinds(r)[id] == pst_cloud_kinds(w)[i];
        ok = ok && pst_cloud_ids(r)[i] == (int64_t)i;
    }
    free(tmp);
    return ok;
}

static void check_round_trip(int dim, int mob)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *w = make_cloud(dim, mob), *r = NULL;
    CHECK(w != NULL);
    const char *p = path_of(dim == 2 ? "rt2.csv" : "rt3.csv");
    CHECK_INT(pst_cloud_write_csv(w, p, err), PST_OK);
    CHECK_INT(pst_cloud_read_csv(&r, p, err), PST_OK);
    if (r) {
        CHECK(same_in_input_order(w, r));
        int kinds[3] = {0, 0, 0};
        for (size_t i = 0; i < pst_cloud_size(r); ++i)
            kinds[pst_cloud_kinds(r)[i]]++;
        CHECK(kinds[0] > 0 && kinds[1] > 0 && kinds[2] == 2);
    }
    /* a second write of the read cloud gives the same bytes */
    const char *p2 = path_of("rt_again.csv");
    static char a[1 << 20], b[1 << 20];
    CHECK_INT(pst_cloud_write_csv(r, p2, err), PST_OK);
    FILE *fa = fopen(p, "rb"), *fb = fopen(path_of("rt_again.csv"), "rb");
    size_t la = fread(a, 1, sizeof a, fa), lb = fread(b, 1, sizeof b, fb);
    fclose(fa);
    fclose(fb);
    CHECK(la == lb && la < sizeof a && !memcmp(a, b, la));
    /* the header as documented */
    const char *head = dim == 2 ? "x,y,V,h,kind,nx,ny," : "x,y,z,V,h,kind,nx,ny,nz,";
    CHECK(!strncmp(a, head, strlen(head)));
    const char *tail = mob == 1   ? ",m,u,rhs_2\n"
                       : dim == 2 ? ",mx,my,u,rhs_2\n"
                                  : ",mx,my,mz,u,rhs_2\n";
    CHECK(strstr(a, tail) != NULL);
    /* a file's mode is 0644 (not mkstemp's 0600) */
    struct stat sb;
    CHECK(stat(p, &sb) == 0 && (sb.st_mode & 0777) == 0644);
    CHECK_INT(leftovers(), 0);
    pst_cloud_destroy(w);
    pst_cloud_destroy(r);
}

static void test_uniform_h_and_numeric_kinds(void)
{
    char err[PST_ERRLEN] = "";
    write_text("plain.csv", "\xEF\xBB\xBFx,y,V,h,kind,nx,ny\r\n"
                            "\r\n"
                            "0, 0, 1, 0.5, 0, 0, 0\r\n"
                            "   \n"
                            "1,0,1,0.5,dirichlet,1,0\n"
                            "0,1,1,0.5,2,0,1"); /* no final newline */
    pst_cloud *c = NULL;
    CHECK_INT(pst_cloud_read_csv(&c, path_of("plain.csv"), err), PST_OK);
    if (c) {
        CHECK_INT(pst_cloud_size(c), 3);
        CHECK_INT(pst_cloud_dim(c), 2);
        CHECK(pst_cloud_h_is_uniform(c) && pst_cloud_h_uniform(c) == 0.5);
        CHECK(pst_cloud_kinds(c)[0] == PST_INTERIOR && pst_cloud_kinds(c)[1] == PST_DIRICHLET &&
              pst_cloud_kinds(c)[2] == PST_NEUMANN);
        CHECK(pst_cloud_coord(c, 0)[1] == 1 && pst_cloud_normal(c, 1)[2] == 1);
        CHECK_INT(pst_cloud_mobility_ncomp(c), 0);
        CHECK_INT(pst_cloud_nfields(c), 0);
    }
    pst_cloud_destroy(c);

    /* a header alone: an empty cloud of the header's dimension */
    write_text("header_only.csv", "x,y,z,V,h,kind,nx,ny,nz\n");
    CHECK_INT(pst_cloud_read_csv(&c, path_of("header_only.csv"), err), PST_OK);
    CHECK(c && pst_cloud_size(c) == 0 && pst_cloud_dim(c) == 3);
    pst_cloud_destroy(c);
}

/* A line longer than any fixed buffer: a number padded with 200000 spaces. */
static void test_long_line(void)
{
    size_t pad = 200000;
    char *text = malloc(pad + 200);
    strcpy(text, "x,y,V,h,kind,nx,ny,f\n0,0,1,1,0,0,0,");
    size_t len = strlen(text);
    memset(text + len, ' ', pad);
    strcpy(text + len + pad, "2.5\n1,0,1,1,0,0,0,3\n");
    write_text("long.csv", text);
    free(text);
    char err[PST_ERRLEN] = "";
    pst_cloud *c = NULL;
    CHECK_INT(pst_cloud_read_csv(&c, path_of("long.csv"), err), PST_OK);
    double *f = c ? pst_cloud_field_by_name(c, "f") : NULL;
    CHECK(f && f[0] == 2.5 && f[1] == 3);
    pst_cloud_destroy(c);
}

/* Read `text`; expect `status` and every needle in the message. */
static void expect_error(const char *text, int status, const char *n1, const char *n2)
{
    write_text("bad.csv", text);
    char err[PST_ERRLEN] = "";
    pst_cloud *c = (pst_cloud *)&c;
    CHECK_INT(pst_cloud_read_csv(&c, path_of("bad.csv"), err), status);
    CHECK(c == NULL);
    int found = strstr(err, n1) && (!n2 || strstr(err, n2));
    CHECK(found);
    if (!found)
        fprintf(stderr, "  message was: %s\n", err);
}

#define HDR "x,y,V,h,kind,nx,ny\n"
#define ROW "0,0,1,1,interior,0,0\n"

static void test_bad_input(void)
{
    /* values: line and column of the offending cell, and its column name */
    expect_error(HDR ROW "1,0,nan,1,interior,0,0\n", PST_EINPUT, "bad.csv:3:3: column V", "finite");
    expect_error(HDR "inf,0,1,1,interior,0,0\n", PST_EINPUT, "bad.csv:2:1: column x", "finite");
    expect_error(HDR ROW "1,-Infinity,1,1,interior,0,0\n", PST_EINPUT, ":3:2: column y", NULL);
    expect_error(HDR ROW "1,0,1,1,interior,0,1e999\n", PST_EINPUT, ":3:7: column ny", "finite");
    expect_error(HDR ROW "1,0,1,1,interior,0\n", PST_EINPUT, ":3:7:",
                 "expected 7 columns, found 6");
    expect_error(HDR ROW "1,0,1,1,interior,0,0,5\n", PST_EINPUT, ":3:8:", "found 8");
    expect_error(HDR "1,0,1,1,wall,0,0\n", PST_EINPUT, ":2:5: column kind", "unknown kind 'wall'");
    expect_error(HDR "1,0,1,1,3,0,0\n", PST_EINPUT, ":2:5:", "unknown kind");
    expect_error(HDR ROW "\n\n1,0,0,1,interior,0,0\n", PST_EINPUT, ":5:3: column V", "> 0");
    expect_error(HDR "1,0,1,-1,interior,0,0\n", PST_EINPUT, ":2:4: column h", "> 0");
    expect_error(HDR "1,0,1,1,interior,0,abc\n", PST_EINPUT, ":2:7:", "cannot parse 'abc'");
    expect_error(HDR "1,0,1,1,interior,0,1.5x\n", PST_EINPUT, ":2:7:", "cannot parse");
    expect_error(HDR "1,,1,1,interior,0,0\n", PST_EINPUT, ":2:2:", "missing value");
    expect_error("x,y,V,h,kind,nx,ny,m\n1,0,1,1,interior,0,0,0\n", PST_EINPUT, ":2:8: column m",
                 "mobility");
    /* duplicates: the later line, naming the earlier one; blank lines count */
    expect_error(HDR "0.5,0.25,1,1,0,0,0\n" ROW "\n0.5,0.25,2,1,0,0,0\n", PST_EINPUT,
                 "bad.csv:5:1: duplicate particle", "line 2");
    /* header problems */
    expect_error("x,y,V,h,kind,nx,nyy\n" ROW, PST_EINPUT, "bad.csv:1:7:", "expected column 'ny'");
    expect_error("y,x,V,h,kind,nx,ny\n" ROW, PST_EINPUT, ":1:1:", "found 'y'");
    expect_error("x,y,h,V,kind,nx,ny\n" ROW, PST_EINPUT, ":1:3:", "'V'");
    expect_error("x,y,V,h,kind,nx\n", PST_EINPUT, ":1:7:", "missing column 'ny'");
    expect_error("x,y,V,h,kind,nx,ny,z\n", PST_EINPUT, ":1:3:", "expected column 'z'");
    expect_error("x,y,V,h,kind,nx,ny,u,u\n", PST_EINPUT, ":1:9:", "duplicate column name 'u'");
    expect_error("x,y,V,h,kind,nx,ny,u,x\n", PST_EINPUT, ":1:9:", "duplicate column name 'x'");
    expect_error("x,y,V,h,kind,nx,ny,u,m\n", PST_EINPUT, ":1:9:", "misplaced column 'm'");
    expect_error("x,y,V,h,kind,nx,ny,mx,mz\n", PST_EINPUT, ":1:9:", "'my'");
    expect_error("x,y,V,h,kind,nx,ny,my\n", PST_EINPUT, ":1:8:", "misplaced");
    expect_error("x,y,V,h,kind,nx,ny,2u\n", PST_EINPUT, ":1:8:", "unknown column '2u'");
    expect_error("x,y,V,h,kind,nx,ny,a\x01\x7f\n", PST_EINPUT, ":1:8:",
                 "unknown column 'a\\x01\\x7f'"); /* control bytes escaped */
    expect_error("", PST_EINPUT, "bad.csv:1:1:", "empty");
    expect_error("\n  \r\n", PST_EINPUT, "bad.csv:1:1:", "no header");
    /* a missing file */
    char err[PST_ERRLEN] = "";
    pst_cloud *c = (pst_cloud *)&c;
    CHECK_INT(pst_cloud_read_csv(&c, path_of("absent.csv"), err), PST_EIO);
    CHECK(c == NULL && strstr(err, "absent.csv: cannot open"));
}

/* The writer under test_under_file_limit: a cloud, the path and the message buffer. */
typedef struct {
    const pst_cloud *c;
    const char *path;
    char *err;
} write_job;

static int write_keep(const void *job)
{
    const write_job *j = job;
    return pst_cloud_write_csv(j->c, j->path, j->err);
}

/* kind and the normals are optional: without them every particle is interior with a zero
 * normal; normals may come without kind, kind without normals (then no particle may be
 * Neumann: its flux row needs the normal). */
static void test_minimal_columns(void)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *c = NULL;
    write_text("min.csv", "x,y,V,h,u\n0,0,1,0.5,3\n1,0,1,0.5,4\n");
    CHECK_INT(pst_cloud_read_csv(&c, path_of("min.csv"), err), PST_OK);
    if (c) {
        CHECK_INT(pst_cloud_size(c), 2);
        CHECK(pst_cloud_kinds(c)[0] == PST_INTERIOR && pst_cloud_kinds(c)[1] == PST_INTERIOR);
        CHECK(pst_cloud_normal(c, 0)[1] == 0 && pst_cloud_normal(c, 1)[1] == 0); /* axis, particle */
        CHECK_INT(pst_cloud_nfields(c), 1);
        CHECK(pst_cloud_field(c, 0)[1] == 4);
    }
    pst_cloud_destroy(c);
    write_text("min3.csv", "x,y,z,V,h,nx,ny,nz,m,u\n0,0,0,1,0.5,0,0,1,2,3\n");
    CHECK_INT(pst_cloud_read_csv(&c, path_of("min3.csv"), err), PST_OK);
    if (c) {
        CHECK(pst_cloud_dim(c) == 3 && pst_cloud_kinds(c)[0] == PST_INTERIOR);
        CHECK(pst_cloud_normal(c, 2)[0] == 1 && pst_cloud_mobility_ncomp(c) == 1);
        CHECK(pst_cloud_field(c, 0)[0] == 3);
    }
    pst_cloud_destroy(c);
    write_text("kinds.csv", "x,y,V,h,kind,u\n0,0,1,0.5,dirichlet,3\n1,0,1,0.5,0,4\n");
    CHECK_INT(pst_cloud_read_csv(&c, path_of("kinds.csv"), err), PST_OK);
    CHECK(c && pst_cloud_kinds(c)[0] == PST_DIRICHLET && pst_cloud_normal(c, 0)[0] == 0);
    pst_cloud_destroy(c);
    expect_error("x,y,V,h,kind\n0,0,1,0.5,neumann\n", PST_EINPUT, "bad.csv: particle 0",
                 "zero normal");
    expect_error("x,y,V,h,nx,u\n", PST_EINPUT, "bad.csv:1:6:", "'ny' of the normal");
    expect_error("x,y,V\n", PST_EINPUT, "bad.csv:1:4:", "missing column 'h'");
}

static void test_write_failures(void)
{
    char err[PST_ERRLEN] = "";
    pst_cloud *c = make_cloud(3, 3);
    /* into a directory that does not exist: EIO, and nothing is created */
    const char *p = path_of("no_such_dir/out.csv");
    CHECK_INT(pst_cloud_write_csv(c, p, err), PST_EIO);
    CHECK(strstr(err, "out.csv") != NULL);
    struct stat sb;
    CHECK(stat(path_of("no_such_dir"), &sb) != 0);

    /* a write that fails half-way (file-size limit) leaves the old file as it was */
    const char *old = "old contents\n";
    write_text("keep.csv", old);
    write_job job = {c, path_of("keep.csv"), err};
    CHECK_INT(test_under_file_limit(4096 /* the cloud needs far more */, write_keep, &job),
              PST_EIO);
    CHECK(strstr(err, "keep.csv") != NULL);
    CHECK(test_file_holds(path_of("keep.csv"), old));
    CHECK_INT(leftovers(), 0);

    /* a directory in the way is refused before anything is written */
    mkdir(path_of("a_dir"), 0755);
    CHECK_INT(pst_cloud_write_csv(c, path_of("a_dir"), err), PST_EIO);
    CHECK(strstr(err, "is a directory") != NULL);
    CHECK_INT(leftovers(), 0);
    rmdir(path_of("a_dir"));

    /* replacing a file keeps its mode */
    chmod(path_of("keep.csv"), 0640);
    CHECK_INT(pst_cloud_write_csv(c, path_of("keep.csv"), err), PST_OK);
    CHECK(stat(path_of("keep.csv"), &sb) == 0 && (sb.st_mode & 0777) == 0640);

    /* ids that are not a permutation cannot give an input order */
    pst_cloud_ids(c)[0] = pst_cloud_ids(c)[1];
    CHECK_INT(pst_cloud_write_csv(c, path_of("ids.csv"), err), PST_EINVAL);
    CHECK(strstr(err, "permutation") != NULL);
    CHECK(stat(path_of("ids.csv"), &sb) != 0);
    pst_cloud_destroy(c);
}

/* HDR plus nf field columns f0, f1, ... (the last one renamed `last` when given), and two
 * rows whose field k holds k (row 1) and -k (row 2). Malloc'd. */
static char *wide_csv(size_t nf, const char *last)
{
    size_t cap = 64 + nf * 24, n = 0;
    char *t = malloc(cap);
    n += (size_t)snprintf(t + n, cap - n, "x,y,V,h,kind,nx,ny");
    for (size_t k = 0; k < nf; ++k)
        n += last && k + 1 == nf ? (size_t)snprintf(t + n, cap - n, ",%s", last)
                                 : (size_t)snprintf(t + n, cap - n, ",f%zu", k);
    for (int r = 0; r < 2; ++r) {
        n += (size_t)snprintf(t + n, cap - n, "\n%d,0,1,1,interior,0,0", r);
        for (size_t k = 0; k < nf; ++k)
            n += (size_t)snprintf(t + n, cap - n, ",%s%zu", r ? "-" : "", k);
    }
    snprintf(t + n, cap - n, "\n");
    return t;
}

/* Many fields (issue 16): the duplicate-name check was pairwise and the set-up per field
 * linear, minutes for a wide file. Now: at most PST_MAX_FIELDS fields, refused with the count
 * and the cap; a repeat found by sorting is still named with its first column. */
static void test_many_fields(void)
{
    char *t = wide_csv(60000, NULL);
    expect_error(t, PST_EINPUT, "bad.csv:1:4104: 60000 field columns, more than the 4096 a cloud "
                                "file may have", NULL);
    free(t);
    t = wide_csv(100000, NULL); /* past the tokenizer's cap on cells */
    expect_error(t, PST_EINPUT, "bad.csv:1:", "more than 65536 cells");
    free(t);
    t = wide_csv(PST_MAX_FIELDS, "f17");
    expect_error(t, PST_EINPUT, "bad.csv:1:4103: duplicate column name 'f17' (also column 25)",
                 NULL);
    free(t);
    t = wide_csv(PST_MAX_FIELDS, NULL);
    write_text("wide.csv", t);
    free(t);
    char err[PST_ERRLEN] = "";
    pst_cloud *c = NULL;
    CHECK_INT(pst_cloud_read_csv(&c, path_of("wide.csv"), err), PST_OK);
    if (!c)
        return;
    CHECK_INT(pst_cloud_nfields(c), PST_MAX_FIELDS);
    CHECK(strcmp(pst_cloud_field_name(c, 4095), "f4095") == 0);
    const double *f = pst_cloud_field_by_name(c, "f4000");
    const int64_t *id = pst_cloud_ids(c);
    int ok = f != NULL;
    for (size_t i = 0; ok && i < 2; ++i)
        ok = f[i] == (id[i] ? -4000.0 : 4000.0);
    CHECK(ok);
    pst_cloud_destroy(c);
}

/* pst_escape_controls: control bytes as \\xNN, the end cut (never inside an escape) to fit. */
static void test_escape_controls(void)
{
    char m[16] = "a\x01\tb\x7f";
    pst_escape_controls(m, sizeof m);
    CHECK(strcmp(m, "a\\x01\\x09b\\x7f") == 0);
    char cut[8] = "ab\x02" "cd";
    pst_escape_controls(cut, sizeof cut); /* "ab\x02" is 6 bytes, "c" fits, "d" does not */
    CHECK(strcmp(cut, "ab\\x02c") == 0);
    char tight[6] = "ab\x02" "c";
    pst_escape_controls(tight, sizeof tight); /* the escape does not fit in 5: cut before it */
    CHECK(strcmp(tight, "ab") == 0);
    char plain[8] = "\xc3\xa9 ok";
    pst_escape_controls(plain, sizeof plain); /* UTF-8 is not a control byte */
    CHECK(strcmp(plain, "\xc3\xa9 ok") == 0);
}

int main(void)
{
    if (test_scratch_dir(dir, sizeof dir, "pst_test_csv") != 0)
        return 1;
    test_tokenizer_quoting();
    test_tokenizer_errors();
    test_tokenizer_caps();
    test_numbers();
    check_round_trip(2, 1);
    check_round_trip(3, 3);
    check_round_trip(2, 2);
    test_uniform_h_and_numeric_kinds();
    test_minimal_columns();
    test_long_line();
    test_bad_input();
    test_many_fields();
    test_escape_controls();
    test_write_failures();
    test_remove_dir(dir);
    return check_summary("test_csv");
}
