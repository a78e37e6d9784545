/* Reading clouds from VTK XML files (.vtu UnstructuredGrid, .vtp PolyData): the subset is in
 * docs/io.md ("Reading VTU"). The whole file is read into memory and a small scanner walks the
 * XML up to the appended block (which is raw bytes, not XML); it keeps only what a cloud
 * needs: the Piece's NumberOfPoints, the Points array and the PointData arrays. Every array is
 * decoded from its source (appended raw, inline base64 "binary" or ascii) after its size has
 * been checked against the bytes that are really there, so a damaged file gives PST_EINPUT
 * naming the file and the place, never a read out of bounds or a huge allocation. Values are
 * checked where they stand, like the CSV reader, with messages that name the array and the
 * point (the 0-based row of the file). */
#include "internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { FMT_APPENDED, FMT_ASCII, FMT_BINARY };
enum { SEC_POINTDATA, SEC_POINTS };

/* The scalar types of VTK's XML format that the reader converts to double. */
static const struct {
    const char *name;
    int size, is_float, is_signed;
} vtk_types[] = {{"Int8", 1, 0, 1},  {"UInt8", 1, 0, 0},  {"Int16", 2, 0, 1},
                 {"UInt16", 2, 0, 0}, {"Int32", 4, 0, 1}, {"UInt32", 4, 0, 0},
                 {"Int64", 8, 0, 1},  {"UInt64", 8, 0, 0}, {"Float32", 4, 1, 1},
                 {"Float64", 8, 1, 1}};
#define NTYPES (sizeof vtk_types / sizeof *vtk_types)

#define MAX_ATTR 32
#define MAX_DEPTH 64
#define NAME_CAP 256

/* One DataArray of the Points or PointData of the Piece. */
typedef struct {
    char name[NAME_CAP];
    size_t at;          /* file offset of its start tag (for LINE:COLUMN) */
    int sec, type, ncomp, format;
    uint64_t offset;    /* appended: into the block after '_' */
    char *text;         /* inline (ascii, binary): the element's own text, NUL-terminated */
    size_t text_len;
} vtu_in_array;

typedef struct {
    const char *path;
    char *err;
    const unsigned char *buf; /* the file, with a NUL after the last byte */
    size_t len;
    size_t pos;               /* scanner position */
    /* from the header */
    int big_endian, header_size, have_piece, have_points;
    uint64_t npoints;
    /* the appended block: [data, data_end) of buf */
    int have_appended, appended_b64;
    size_t data, data_end;
    /* the arrays */
    vtu_in_array *a;
    size_t na, cap;
    vtu_in_array points;
} reader;

/* An XML tag: name and attributes as ranges of the file. */
typedef struct {
    size_t at, name, name_len;
    size_t an[MAX_ATTR], an_len[MAX_ATTR], av[MAX_ATTR], av_len[MAX_ATTR];
    int nattr, closing, empty;
} xtag;

/* ---- messages ----------------------------------------------------------------------------- */

/* "FILE:LINE:COLUMN: message" for a place in the XML. */
__attribute__((format(printf, 3, 4))) static int fail_at(reader *r, size_t off,
                                                         const char *fmt, ...)
{
    char msg[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    size_t line = 1, col = 1;
    for (size_t k = 0; k < off && k < r->len; ++k) {
        if (r->buf[k] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    pst_set_err(r->err, "%s:%zu:%zu: %s", r->path, line, col, msg);
    return PST_EINPUT;
}

/* "FILE: message" (values, appended data). */
__attribute__((format(printf, 2, 3))) static int fail(reader *r, const char *fmt, ...)
{
    char msg[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    pst_set_err(r->err, "%s: %s", r->path, msg);
    return PST_EINPUT;
}

static int oom(reader *r)
{
    pst_set_err(r->err, "%s: out of memory", r->path);
    return PST_ENOMEM;
}

/* ---- the XML scanner ---------------------------------------------------------------------- */

static int is_space(int ch) { return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r'; }

static int is_name_char(int ch)
{
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
           ch == '_' || ch == ':' || ch == '.' || ch == '-';
}

static int name_is(const reader *r, size_t at, size_t len, const char *s)
{
    return strlen(s) == len && memcmp(r->buf + at, s, len) == 0;
}

/* Skip to just after `end` (a NUL-free string); 0 when the file ends first. */
static int skip_past(reader *r, const char *end)
{
    size_t m = strlen(end);
    for (size_t k = r->pos; k + m <= r->len; ++k)
        if (memcmp(r->buf + k, end, m) == 0) {
            r->pos = k + m;
            return 1;
        }
    return 0;
}

/* Parse the tag at r->pos (a '<' that opens an element or an end tag). */
static int parse_tag(reader *r, xtag *t)
{
    const unsigned char *b = r->buf;
    size_t p = r->pos, n = r->len;
    memset(t, 0, sizeof *t);
    t->at = p++;
    if (p < n && b[p] == '/') {
        t->closing = 1;
        ++p;
    }
    t->name = p;
    while (p < n && is_name_char(b[p]))
        ++p;
    t->name_len = p - t->name;
    if (t->name_len == 0)
        return fail_at(r, t->at, "malformed XML: expected an element name after '<'");
    for (;;) {
        while (p < n && is_space(b[p]))
            ++p;
        if (p >= n)
            return fail_at(r, t->at, "truncated file: the tag <%.*s is not closed",
                           (int)(t->name_len < 64 ? t->name_len : 64), (const char *)b + t->name);
        if (b[p] == '>') {
            r->pos = p + 1;
            return PST_OK;
        }
        if (!t->closing && b[p] == '/' && p + 1 < n && b[p + 1] == '>') {
            t->empty = 1;
            r->pos = p + 2;
            return PST_OK;
        }
        if (t->closing || !is_name_char(b[p]))
            return fail_at(r, p, "malformed XML: unexpected character '%c' in a tag",
                           b[p] >= 32 && b[p] < 127 ? b[p] : '?');
        if (t->nattr == MAX_ATTR)
            return fail_at(r, p, "malformed XML: more than %d attributes in one tag", MAX_ATTR);
        size_t an = p;
        while (p < n && is_name_char(b[p]))
            ++p;
        size_t an_len = p - an;
        while (p < n && is_space(b[p]))
            ++p;
        if (p >= n || b[p] != '=')
            return fail_at(r, p, "malformed XML: expected '=' after attribute %.*s",
                           (int)(an_len < 64 ? an_len : 64), (const char *)b + an);
        ++p;
        while (p < n && is_space(b[p]))
            ++p;
        if (p >= n || (b[p] != '"' && b[p] != '\''))
            return fail_at(r, p, "malformed XML: expected a quoted value of attribute %.*s",
                           (int)(an_len < 64 ? an_len : 64), (const char *)b + an);
        unsigned char q = b[p++];
        size_t av = p;
        while (p < n && b[p] != q && b[p] != '<')
            ++p;
        if (p >= n || b[p] != q)
            return fail_at(r, av - 1, "malformed XML: unterminated value of attribute %.*s",
                           (int)(an_len < 64 ? an_len : 64), (const char *)b + an);
        t->an[t->nattr] = an;
        t->an_len[t->nattr] = an_len;
        t->av[t->nattr] = av;
        t->av_len[t->nattr] = p - av;
        ++t->nattr;
        ++p;
    }
}

/* Copy attribute `key` of `t` into out (cap bytes) with the five predefined entities decoded.
 * 1: found, 0: absent, -1: too long for out. */
static int get_attr(const reader *r, const xtag *t, const char *key, char *out, size_t cap)
{
    static const char *const ent[][2] = {
        {"&lt;", "<"}, {"&gt;", ">"}, {"&amp;", "&"}, {"&quot;", "\""}, {"&apos;", "'"}};
    for (int k = 0; k < t->nattr; ++k) {
        if (!name_is(r, t->an[k], t->an_len[k], key))
            continue;
        const char *v = (const char *)r->buf + t->av[k];
        size_t len = t->av_len[k], o = 0;
        for (size_t i = 0; i < len;) {
            const char *rep = NULL;
            size_t adv = 1;
            if (v[i] == '&')
                for (size_t e = 0; e < 5; ++e) {
                    size_t el = strlen(ent[e][0]);
                    if (i + el <= len && memcmp(v + i, ent[e][0], el) == 0) {
                        rep = ent[e][1];
                        adv = el;
                        break;
                    }
                }
            if (o + 1 >= cap)
                return -1;
            out[o++] = rep ? rep[0] : v[i];
            i += adv;
        }
        out[o] = '\0';
        return 1;
    }
    return 0;
}

/* An attribute parsed as a non-negative decimal integer; 1 found, 0 absent, error otherwise. */
static int get_uint(reader *r, const xtag *t, const char *key, uint64_t *v, uint64_t max)
{
    char s[64];
    int got = get_attr(r, t, key, s, sizeof s);
    if (got == 0)
        return 0;
    if (got < 0) {
        fail_at(r, t->at, "attribute %s is too long", key);
        return -1;
    }
    char *p = s;
    while (is_space(*p))
        ++p;
    uint64_t x = 0;
    int digits = 0;
    for (; *p >= '0' && *p <= '9'; ++p, ++digits) {
        if (x > (max - (uint64_t)(*p - '0')) / 10) {
            fail_at(r, t->at, "attribute %s exceeds the limit %llu", key,
                    (unsigned long long)max);
            return -1;
        }
        x = 10 * x + (uint64_t)(*p - '0');
    }
    while (is_space(*p))
        ++p;
    if (!digits || *p) {
        fail_at(r, t->at, "attribute %s=\"%.32s\" is not a non-negative integer", key, s);
        return -1;
    }
    *v = x;
    return 1;
}

/* ---- the structure of the file ------------------------------------------------------------ */

enum { E_OTHER, E_VTKFILE, E_DATASET, E_PIECE, E_POINTDATA, E_POINTS, E_ARRAY, E_SKIP };

/* <VTKFile ...>: dataset type, byte order, header type, compressor. */
static int root_tag(reader *r, const xtag *t, char *dataset, size_t cap)
{
    char s[64];
    if (!name_is(r, t->name, t->name_len, "VTKFile"))
        return fail_at(r, t->at, "not a VTK XML file: the root element is <%.*s>, not <VTKFile>",
                       (int)(t->name_len < 64 ? t->name_len : 64),
                       (const char *)r->buf + t->name);
    int got = get_attr(r, t, "type", dataset, cap);
    if (got <= 0 || (strcmp(dataset, "UnstructuredGrid") && strcmp(dataset, "PolyData")))
        return fail_at(r, t->at, "unsupported dataset type \"%.64s\" (UnstructuredGrid or "
                                 "PolyData)",
                       got > 0 ? dataset : "");
    got = get_attr(r, t, "compressor", s, sizeof s);
    if (got != 0 && !(got > 0 && s[0] == '\0'))
        return fail_at(r, t->at, "compressed VTU is not supported: write it uncompressed (e.g. "
                                 "ParaView: Save Data, uncheck compression)");
    got = get_attr(r, t, "byte_order", s, sizeof s);
    if (got > 0 && !strcmp(s, "BigEndian"))
        r->big_endian = 1;
    else if (got != 0 && !(got > 0 && !strcmp(s, "LittleEndian")))
        return fail_at(r, t->at, "unknown byte_order (LittleEndian or BigEndian)");
    got = get_attr(r, t, "header_type", s, sizeof s);
    r->header_size = 4; /* VTK's default (file version 0.1) */
    if (got > 0 && !strcmp(s, "UInt64"))
        r->header_size = 8;
    else if (got != 0 && !(got > 0 && !strcmp(s, "UInt32")))
        return fail_at(r, t->at, "unsupported header_type \"%.32s\" (UInt32 or UInt64)",
                       got > 0 ? s : "");
    return PST_OK;
}

/* <DataArray ...> of the Points or the PointData. */
static int array_tag(reader *r, const xtag *t, int sec, vtu_in_array **out)
{
    vtu_in_array *a;
    if (sec == SEC_POINTS) {
        if (r->have_points)
            return fail_at(r, t->at, "<Points> holds more than one DataArray");
        r->have_points = 1;
        a = &r->points;
    } else {
        if (r->na == r->cap) {
            size_t cap = r->cap ? 2 * r->cap : 16;
            vtu_in_array *na = realloc(r->a, cap * sizeof *na);
            if (!na)
                return oom(r);
            r->a = na;
            r->cap = cap;
        }
        a = &r->a[r->na++];
    }
    memset(a, 0, sizeof *a);
    a->at = t->at;
    a->sec = sec;
    int got = get_attr(r, t, "Name", a->name, sizeof a->name);
    if (got < 0)
        return fail_at(r, t->at, "DataArray name longer than %d characters", NAME_CAP - 1);
    if (got == 0 && sec == SEC_POINTDATA)
        return fail_at(r, t->at, "PointData DataArray without a Name");
    if (got == 0)
        strcpy(a->name, "Points");
    char s[32];
    got = get_attr(r, t, "type", s, sizeof s);
    a->type = -1;
    for (size_t k = 0; got > 0 && k < NTYPES; ++k)
        if (!strcmp(s, vtk_types[k].name))
            a->type = (int)k;
    if (a->type < 0)
        return fail_at(r, t->at, "array '%.64s': unsupported type \"%.32s\" (Float64, Float32, "
                                 "Int8..Int64, UInt8..UInt64)",
                       a->name, got > 0 ? s : "");
    uint64_t v = 1;
    got = get_uint(r, t, "NumberOfComponents", &v, 1024);
    if (got < 0)
        return PST_EINPUT;
    if (v < 1)
        return fail_at(r, t->at, "array '%.64s': NumberOfComponents must be >= 1", a->name);
    a->ncomp = (int)v;
    got = get_attr(r, t, "format", s, sizeof s);
    if (got > 0 && !strcmp(s, "appended"))
        a->format = FMT_APPENDED;
    else if (got > 0 && !strcmp(s, "ascii"))
        a->format = FMT_ASCII;
    else if (got > 0 && !strcmp(s, "binary"))
        a->format = FMT_BINARY;
    else
        return fail_at(r, t->at, "array '%.64s': format must be appended, binary or ascii",
                       a->name);
    if (a->format == FMT_APPENDED) {
        got = get_uint(r, t, "offset", &a->offset, UINT64_MAX);
        if (got < 0)
            return PST_EINPUT;
        if (got == 0)
            return fail_at(r, t->at, "array '%.64s': format=\"appended\" without an offset",
                           a->name);
    }
    got = get_uint(r, t, "NumberOfTuples", &v, UINT64_MAX);
    if (got < 0)
        return PST_EINPUT;
    if (got > 0 && v != r->npoints)
        return fail_at(r, t->at, "array '%.64s' has NumberOfTuples=%llu but the piece has %llu "
                                 "points",
                       a->name, (unsigned long long)v, (unsigned long long)r->npoints);
    *out = a;
    return PST_OK;
}

/* Append text [from, to) of the file to an inline array's content. */
static int add_text(reader *r, vtu_in_array *a, size_t from, size_t to)
{
    if (to <= from)
        return PST_OK;
    char *s = realloc(a->text, a->text_len + (to - from) + 1);
    if (!s)
        return oom(r);
    memcpy(s + a->text_len, r->buf + from, to - from);
    a->text = s;
    a->text_len += to - from;
    s[a->text_len] = '\0';
    return PST_OK;
}

/* Walk the XML: the root, the dataset element, the one Piece with its Points and PointData,
 * and the AppendedData element (where the scan stops). Everything else is skipped. */
static int scan_xml(reader *r)
{
    int kind[MAX_DEPTH];
    size_t open_at[MAX_DEPTH], open_name[MAX_DEPTH], open_len[MAX_DEPTH];
    int depth = 0, done = 0, npieces = 0;
    char dataset[32] = "";
    vtu_in_array *inl = NULL; /* the inline array whose text is being collected */
    int st;
    r->pos = 0;
    if (r->len >= 3 && !memcmp(r->buf, "\xEF\xBB\xBF", 3))
        r->pos = 3;
    for (;;) {
        size_t text = r->pos;
        const unsigned char *lt = memchr(r->buf + r->pos, '<', r->len - r->pos);
        size_t at = lt ? (size_t)(lt - r->buf) : r->len;
        if (inl && depth > 0 && kind[depth - 1] == E_ARRAY &&
            (st = add_text(r, inl, text, at)) != PST_OK)
            return st;
        if (!lt)
            break;
        r->pos = at;
        const char *p = (const char *)lt;
        size_t left = r->len - at;
        if (left >= 4 && !memcmp(p, "<!--", 4)) {
            if (!skip_past(r, "-->"))
                return fail_at(r, at, "truncated file: unterminated comment");
            continue;
        }
        if (left >= 2 && (p[1] == '?' || p[1] == '!')) {
            if (left >= 9 && !memcmp(p, "<![CDATA[", 9))
                return fail_at(r, at, "CDATA sections are not supported");
            if (!skip_past(r, p[1] == '?' ? "?>" : ">"))
                return fail_at(r, at, "truncated file: unterminated <%c", p[1]);
            continue;
        }
        if (done)
            return fail_at(r, at, "malformed XML: content after </VTKFile>");
        xtag t;
        if ((st = parse_tag(r, &t)) != PST_OK)
            return st;
        if (t.closing) {
            if (depth == 0 || open_len[depth - 1] != t.name_len ||
                memcmp(r->buf + t.name, r->buf + open_name[depth - 1], t.name_len) != 0)
                return fail_at(r, t.at, "malformed XML: unexpected end tag </%.*s>",
                               (int)(t.name_len < 64 ? t.name_len : 64),
                               (const char *)r->buf + t.name);
            if (kind[depth - 1] == E_ARRAY)
                inl = NULL;
            --depth;
            done = depth == 0;
            continue;
        }
        if (depth == MAX_DEPTH)
            return fail_at(r, t.at, "malformed XML: elements nested deeper than %d", MAX_DEPTH);
        int parent = depth ? kind[depth - 1] : -1, k = E_SKIP;
        if (depth == 0) {
            if ((st = root_tag(r, &t, dataset, sizeof dataset)) != PST_OK)
                return st;
            k = E_VTKFILE;
        } else if (parent == E_VTKFILE && name_is(r, t.name, t.name_len, "AppendedData")) {
            char enc[32];
            int got = get_attr(r, &t, "encoding", enc, sizeof enc);
            if (got > 0 && !strcmp(enc, "base64"))
                r->appended_b64 = 1;
            else if (got <= 0 || strcmp(enc, "raw"))
                return fail_at(r, t.at, "AppendedData encoding \"%.31s\" is not supported "
                                        "(raw or base64)",
                               got > 0 ? enc : "");
            size_t q = r->pos;
            while (q < r->len && is_space(r->buf[q]))
                ++q;
            if (t.empty || q >= r->len || r->buf[q] != '_')
                return fail_at(r, q, "AppendedData does not start with '_'");
            r->have_appended = 1;
            r->data = q + 1;
            /* the block ends at the last </AppendedData> of the file */
            static const char end_tag[] = "</AppendedData>";
            size_t m = sizeof end_tag - 1;
            r->data_end = 0;
            for (size_t e = r->len; e >= r->data + m; --e)
                if (!memcmp(r->buf + e - m, end_tag, m)) {
                    r->data_end = e - m;
                    break;
                }
            if (r->data_end < r->data)
                return fail(r, "truncated file: no </AppendedData> after the appended data "
                               "(which starts at byte %zu)",
                            r->data);
            if (depth != 1)
                return fail_at(r, t.at, "malformed XML: <AppendedData> inside an element");
            break;
        } else if (parent == E_VTKFILE && name_is(r, t.name, t.name_len, dataset)) {
            k = E_DATASET;
        } else if (parent == E_DATASET && name_is(r, t.name, t.name_len, "Piece")) {
            if (++npieces > 1)
                return fail_at(r, t.at, "more than one Piece: only single-piece files are "
                                        "supported");
            int got = get_uint(r, &t, "NumberOfPoints", &r->npoints, UINT32_MAX);
            if (got < 0)
                return PST_EINPUT;
            if (got == 0)
                return fail_at(r, t.at, "Piece without NumberOfPoints");
            r->have_piece = 1;
            k = E_PIECE;
        } else if (parent == E_PIECE && name_is(r, t.name, t.name_len, "PointData")) {
            k = E_POINTDATA;
        } else if (parent == E_PIECE && name_is(r, t.name, t.name_len, "Points")) {
            k = E_POINTS;
        } else if ((parent == E_POINTDATA || parent == E_POINTS) &&
                   name_is(r, t.name, t.name_len, "DataArray")) {
            vtu_in_array *a = NULL;
            st = array_tag(r, &t, parent == E_POINTS ? SEC_POINTS : SEC_POINTDATA, &a);
            if (st != PST_OK)
                return st;
            if (a->format != FMT_APPENDED) {
                a->text = malloc(1); /* an empty element has empty text */
                if (!a->text)
                    return oom(r);
                a->text[0] = '\0';
                inl = a;
            }
            k = E_ARRAY;
        }
        if (t.empty) {
            if (k == E_ARRAY)
                inl = NULL;
            if (depth == 0)
                return fail_at(r, t.at, "empty <VTKFile/>: no dataset");
            continue;
        }
        kind[depth] = k;
        open_at[depth] = t.at;
        open_name[depth] = t.name;
        open_len[depth] = t.name_len;
        ++depth;
    }
    if (depth > 0 && !r->have_appended)
        return fail_at(r, open_at[depth - 1], "truncated file: <%.*s> is not closed",
                       (int)(open_len[depth - 1] < 64 ? open_len[depth - 1] : 64),
                       (const char *)r->buf + open_name[depth - 1]);
    if (!done && !r->have_appended)
        return fail(r, "not a VTK XML file: no <VTKFile> element");
    if (!r->have_piece)
        return fail(r, "no <Piece> in the <%s>", dataset);
    if (!r->have_points && r->npoints > 0)
        return fail(r, "the Piece has %llu points but no <Points> array",
                    (unsigned long long)r->npoints);
    return PST_OK;
}

/* ---- decoding the values ------------------------------------------------------------------ */

static uint64_t load_uint(const unsigned char *p, int size, int big)
{
    uint64_t v = 0;
    for (int b = 0; b < size; ++b)
        v = v << 8 | p[big ? b : size - 1 - b];
    return v;
}

/* One value of type `type` stored at p, as a double. */
static double load_value(const unsigned char *p, int type, int big)
{
    int size = vtk_types[type].size;
    uint64_t u = load_uint(p, size, big);
    if (vtk_types[type].is_float) {
        if (size == 8) {
            double d;
            memcpy(&d, &u, sizeof d);
            return d;
        }
        uint32_t u32 = (uint32_t)u;
        float f;
        memcpy(&f, &u32, sizeof f);
        return f;
    }
    if (!vtk_types[type].is_signed)
        return (double)u;
    if (size < 8 && (u >> (8 * size - 1)) & 1)
        u |= ~(uint64_t)0 << (8 * size); /* sign-extend */
    return (double)(int64_t)u;
}

static int b64_value(int ch)
{
    if (ch >= 'A' && ch <= 'Z')
        return ch - 'A';
    if (ch >= 'a' && ch <= 'z')
        return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9')
        return ch - '0' + 52;
    return ch == '+' ? 62 : ch == '/' ? 63 : -1;
}

/* Decode base64 in place (the output is never longer than the input). Padding may end any
 * quantum, so separately encoded blocks that follow one another decode too. -1 on a bad
 * character (its index in *bad). */
static long long b64_decode(char *s, size_t len, size_t *bad)
{
    size_t o = 0;
    int q[4] = {0, 0, 0, 0}, nq = 0, pad = 0;
    for (size_t i = 0; i <= len; ++i) {
        int ch = i < len ? (unsigned char)s[i] : -1;
        if (ch >= 0 && is_space(ch))
            continue;
        if (ch == '=') {
            if (nq < 2) {
                *bad = i;
                return -1;
            }
            ++pad;
            if (nq + pad < 4)
                continue;
        } else if (ch >= 0) {
            int v = b64_value(ch);
            if (v < 0 || pad) {
                *bad = i;
                return -1;
            }
            q[nq++] = v;
            if (nq < 4)
                continue;
        } else if (nq == 0) {
            break;
        } else if (nq == 1) {
            *bad = i;
            return -1;
        }
        /* a full quantum, a padded one, or an unpadded end */
        unsigned char bytes[3] = {(unsigned char)(q[0] << 2 | q[1] >> 4),
                                  (unsigned char)((q[1] & 15) << 4 | (nq > 2 ? q[2] >> 2 : 0)),
                                  (unsigned char)((nq > 2 ? (q[2] & 3) << 6 : 0) |
                                                  (nq > 3 ? q[3] : 0))};
        for (int k = 0; k < nq - 1; ++k)
            s[o++] = (char)bytes[k];
        nq = pad = 0;
    }
    return (long long)o;
}

/* A base64 stream in the appended block, decoded on demand (bytes of a quantum that the
 * caller did not take yet wait in pend). */
typedef struct {
    const unsigned char *s;
    size_t len, pos;
    unsigned char pend[3];
    int npend;
} b64_stream;

/* Take up to `want` bytes; returns how many were produced (fewer at the end of the block or at
 * a character that is not base64, padding or white space). */
static size_t b64_take(b64_stream *b, unsigned char *out, size_t want)
{
    size_t o = 0;
    while (o < want) {
        if (b->npend > 0) {
            out[o++] = b->pend[0];
            b->pend[0] = b->pend[1];
            b->pend[1] = b->pend[2];
            --b->npend;
            continue;
        }
        int q[4] = {0, 0, 0, 0}, nq = 0;
        while (nq < 4 && b->pos < b->len) {
            int ch = b->s[b->pos];
            if (is_space(ch)) {
                ++b->pos;
                continue;
            }
            if (ch == '=' && nq >= 2) { /* padding ends this quantum */
                for (int pad = 4 - nq; pad > 0 && b->pos < b->len && b->s[b->pos] == '=';
                     --pad)
                    ++b->pos;
                break;
            }
            int v = b64_value(ch);
            if (v < 0)
                break;
            q[nq++] = v;
            ++b->pos;
        }
        if (nq < 2)
            break;
        b->pend[0] = (unsigned char)(q[0] << 2 | q[1] >> 4);
        b->pend[1] = (unsigned char)((q[1] & 15) << 4 | q[2] >> 2);
        b->pend[2] = (unsigned char)((q[2] & 3) << 6 | q[3]);
        b->npend = nq - 1;
        if (nq < 4) /* a padded or final quantum: the stream may go on after it */
            continue;
    }
    return o;
}

/* The declared byte count of a block: n * ncomp * size. */
static uint64_t expect_bytes(const reader *r, const vtu_in_array *a)
{
    return r->npoints * (uint64_t)a->ncomp * (uint64_t)vtk_types[a->type].size;
}

/* Convert count values of a binary block to doubles. */
static void convert(const reader *r, const vtu_in_array *a, const unsigned char *p, double *out,
                    size_t count)
{
    int size = vtk_types[a->type].size;
    for (size_t k = 0; k < count; ++k)
        out[k] = load_value(p + k * (size_t)size, a->type, r->big_endian);
}

/* Decode array a (npoints * ncomp values) into out. */
static int decode(reader *r, vtu_in_array *a, double *out)
{
    size_t count = (size_t)r->npoints * (size_t)a->ncomp;
    uint64_t want = expect_bytes(r, a);
    int hs = r->header_size;
    if (a->format == FMT_APPENDED) {
        if (!r->have_appended)
            return fail_at(r, a->at, "array '%.64s' is format=\"appended\" but the file has no "
                                     "<AppendedData>",
                           a->name);
        size_t avail = r->data_end - r->data;
        if (a->offset > avail || avail - a->offset < (uint64_t)hs)
            return fail(r, "appended data offset %llu (array '%.64s'): beyond the end of the "
                           "appended block (%zu bytes)",
                        (unsigned long long)a->offset, a->name, avail);
        const unsigned char *p = r->buf + r->data + a->offset;
        if (r->appended_b64) {
            b64_stream b = {.s = p, .len = avail - a->offset};
            unsigned char hdr[8];
            if (b64_take(&b, hdr, (size_t)hs) != (size_t)hs)
                return fail(r, "appended data offset %llu (array '%.64s'): truncated or "
                               "invalid base64 header",
                            (unsigned long long)a->offset, a->name);
            uint64_t bytes = load_uint(hdr, hs, r->big_endian);
            if (bytes != want)
                return fail(r, "appended data offset %llu (array '%.64s'): byte count %llu, "
                               "expected %llu (%llu points x %d components x %d bytes)",
                            (unsigned long long)a->offset, a->name, (unsigned long long)bytes,
                            (unsigned long long)want, (unsigned long long)r->npoints, a->ncomp,
                            vtk_types[a->type].size);
            if (bytes / 3 > (b.len - b.pos) / 4 + 1)
                return fail(r, "appended data offset %llu (array '%.64s'): truncated: %llu bytes "
                               "of data do not fit in the rest of the block",
                            (unsigned long long)a->offset, a->name, (unsigned long long)bytes);
            unsigned char *raw = malloc(bytes ? (size_t)bytes : 1);
            if (!raw)
                return oom(r);
            size_t got = b64_take(&b, raw, (size_t)bytes);
            if (got != bytes) {
                free(raw);
                return fail(r, "appended data offset %llu (array '%.64s'): truncated or invalid "
                               "base64 data: %zu of %llu bytes",
                            (unsigned long long)a->offset, a->name, got,
                            (unsigned long long)bytes);
            }
            convert(r, a, raw, out, count);
            free(raw);
            return PST_OK;
        }
        uint64_t bytes = load_uint(p, hs, r->big_endian);
        if (bytes != want)
            return fail(r, "appended data offset %llu (array '%.64s'): byte count %llu, expected "
                           "%llu (%llu points x %d components x %d bytes)",
                        (unsigned long long)a->offset, a->name, (unsigned long long)bytes,
                        (unsigned long long)want, (unsigned long long)r->npoints, a->ncomp,
                        vtk_types[a->type].size);
        if (bytes > avail - a->offset - (uint64_t)hs)
            return fail(r, "appended data offset %llu (array '%.64s'): truncated: %llu bytes of "
                           "data, only %llu left in the appended block",
                        (unsigned long long)a->offset, a->name, (unsigned long long)bytes,
                        (unsigned long long)(avail - a->offset - (uint64_t)hs));
        convert(r, a, p + hs, out, count);
        return PST_OK;
    }
    if (a->format == FMT_BINARY) {
        size_t bad = 0;
        long long got = b64_decode(a->text, a->text_len, &bad);
        if (got < 0)
            return fail_at(r, a->at, "array '%.64s': invalid base64 at character %zu of its "
                                     "data",
                           a->name, bad + 1);
        const unsigned char *p = (const unsigned char *)a->text;
        if ((uint64_t)got < (uint64_t)hs)
            return fail_at(r, a->at, "array '%.64s': truncated binary data: %lld bytes, no "
                                     "room for the %d-byte header",
                           a->name, got, hs);
        uint64_t bytes = load_uint(p, hs, r->big_endian);
        if (bytes != want)
            return fail_at(r, a->at, "array '%.64s': binary byte count %llu, expected %llu "
                                     "(%llu points x %d components x %d bytes)",
                           a->name, (unsigned long long)bytes, (unsigned long long)want,
                           (unsigned long long)r->npoints, a->ncomp, vtk_types[a->type].size);
        if ((uint64_t)got - (uint64_t)hs != bytes)
            return fail_at(r, a->at, "array '%.64s': binary data holds %llu bytes after the "
                                     "header, the header says %llu",
                           a->name, (unsigned long long)((uint64_t)got - (uint64_t)hs),
                           (unsigned long long)bytes);
        convert(r, a, p + hs, out, count);
        return PST_OK;
    }
    /* ascii: white-space separated numbers */
    char *s = a->text;
    size_t k = 0;
    for (;;) {
        while (is_space((unsigned char)*s))
            ++s;
        if (!*s)
            break;
        char *end;
        errno = 0;
        double v = strtod(s, &end); /* ERANGE on subnormals is fine */
        if (end == s || (*end && !is_space((unsigned char)*end))) {
            size_t tl = 0;
            while (s[tl] && !is_space((unsigned char)s[tl]))
                ++tl;
            return fail_at(r, a->at, "array '%.64s': value %zu: cannot parse '%.*s' as a "
                                     "number",
                           a->name, k + 1, (int)(tl < 40 ? tl : 40), s);
        }
        if (k < count)
            out[k] = v;
        ++k;
        s = end;
    }
    if (k != count)
        return fail_at(r, a->at, "array '%.64s' holds %zu values, expected %zu (%llu points x "
                                 "%d components)",
                       a->name, k, count, (unsigned long long)r->npoints, a->ncomp);
    return PST_OK;
}

/* ---- the cloud ---------------------------------------------------------------------------- */

/* The roles of PointData arrays. */
enum { R_FIELD, R_ID, R_KIND, R_V, R_H, R_NORMAL, R_MSCALAR, R_MDIAG, R_STATUS };

static int role_of(const char *name)
{
    static const char *const names[] = {"id", "kind", "V", "h", "normal", "m", "M", "status"};
    for (int k = 0; k < 8; ++k)
        if (!strcmp(name, names[k]))
            return k + 1;
    return R_FIELD;
}

/* Names, component counts and the required arrays, before any value is decoded. */
static int check_arrays(reader *r, size_t *idx_V, size_t *idx_h)
{
    *idx_V = *idx_h = SIZE_MAX;
    int have_m = 0;
    for (size_t k = 0; k < r->na; ++k) {
        vtu_in_array *a = &r->a[k];
        for (size_t j = 0; j < k; ++j)
            if (!strcmp(r->a[j].name, a->name))
                return fail_at(r, a->at, "two PointData arrays are named '%.64s'", a->name);
        int role = role_of(a->name);
        if (role == R_STATUS)
            continue;
        if (role == R_FIELD && (!pst_is_identifier(a->name) ||
                                pst_is_reserved_column(a->name)))
            return fail_at(r, a->at, "PointData array '%.64s' cannot be a field: field names "
                                     "are C identifiers shorter than %d characters and not one "
                                     "of x, y, z, nx, ny, nz, mx, my, mz",
                           a->name, PST_MAX_NAME);
        int want = role == R_NORMAL || role == R_MDIAG ? 3 : 1;
        if (a->ncomp != want) {
            if (role == R_FIELD)
                return fail_at(r, a->at, "PointData array '%.64s' has %d components: only "
                                         "'normal' and 'M' may have more than one (3)",
                               a->name, a->ncomp);
            return fail_at(r, a->at, "PointData array '%s' has %d components, expected %d",
                           a->name, a->ncomp, want);
        }
        if (role == R_MSCALAR || role == R_MDIAG) {
            if (have_m)
                return fail_at(r, a->at, "both 'm' and 'M' are present: give one mobility");
            have_m = 1;
        }
        if (role == R_V)
            *idx_V = k;
        if (role == R_H)
            *idx_h = k;
    }
    if (*idx_V == SIZE_MAX)
        return fail(r, "missing PointData array 'V' (the volumes; required)");
    if (*idx_h == SIZE_MAX)
        return fail(r, "missing PointData array 'h' (the smoothing lengths; required)");
    if (r->have_points && r->points.ncomp != 3)
        return fail_at(r, r->points.at, "the Points array has %d components, expected 3",
                       r->points.ncomp);
    return PST_OK;
}

/* Non-finite values of an array: the first one, by point and component. */
static int check_finite(reader *r, const vtu_in_array *a, const double *v)
{
    size_t count = (size_t)r->npoints * (size_t)a->ncomp;
    for (size_t k = 0; k < count; ++k)
        if (!isfinite(v[k])) {
            if (a->ncomp > 1)
                return fail(r, "array '%.64s', point %zu, component %zu: value %g is not "
                               "finite",
                            a->name, k / (size_t)a->ncomp, k % (size_t)a->ncomp, v[k]);
            return fail(r, "array '%.64s', point %zu: value %g is not finite", a->name, k, v[k]);
        }
    return PST_OK;
}

/* Store one PointData array (values v, file row k -> particle part[k]) into the cloud. */
static int store_array(reader *r, pst_cloud *c, const vtu_in_array *a, const double *v,
                       const size_t *part, size_t field)
{
    size_t n = c->n;
    int dim = c->dim, role = role_of(a->name);
    int st = check_finite(r, a, v);
    if (st != PST_OK)
        return st;
    for (size_t k = 0; k < n; ++k) {
        size_t i = part[k];
        switch (role) {
        case R_KIND:
            if (!(v[k] == 0 || v[k] == 1 || v[k] == 2))
                return fail(r, "array 'kind', point %zu: unknown kind %g (0 interior, 1 "
                               "dirichlet, 2 neumann)",
                            k, v[k]);
            c->kind[i] = (uint8_t)v[k];
            break;
        case R_V:
            if (!(v[k] > 0))
                return fail(r, "array 'V', point %zu: volume V = %.17g must be > 0", k, v[k]);
            c->V[i] = v[k];
            break;
        case R_H:
            if (!(v[k] > 0))
                return fail(r, "array 'h', point %zu: smoothing length h = %.17g must be > 0", k,
                            v[k]);
            if (c->h)
                c->h[i] = v[k];
            break;
        case R_NORMAL:
            for (int d = 0; d < dim; ++d)
                c->normal[d][i] = v[3 * k + (size_t)d];
            break;
        case R_MSCALAR:
        case R_MDIAG:
            for (int m = 0; m < c->mob_ncomp; ++m) {
                double x = v[(size_t)a->ncomp * k + (size_t)m];
                if (!(x > 0))
                    return fail(r, "array '%s', point %zu: mobility %.17g must be > 0", a->name,
                                k, x);
                c->mob[m][i] = x;
            }
            break;
        case R_FIELD:
            c->field[field][i] = v[k];
            break;
        default: /* id (already used), status (ignored) */
            break;
        }
    }
    return PST_OK;
}

/* The particle of each file row: part[k] = id[k] when there is an 'id' array, else k. */
static int make_order(reader *r, double *tmp, size_t *part, size_t *row)
{
    size_t n = (size_t)r->npoints;
    vtu_in_array *id = NULL;
    for (size_t k = 0; k < r->na; ++k)
        if (role_of(r->a[k].name) == R_ID)
            id = &r->a[k];
    for (size_t k = 0; k < n; ++k)
        part[k] = row[k] = k;
    if (!id)
        return PST_OK;
    int st = decode(r, id, tmp);
    if (st != PST_OK)
        return st;
    for (size_t k = 0; k < n; ++k)
        row[k] = SIZE_MAX;
    for (size_t k = 0; k < n; ++k) {
        double v = tmp[k];
        if (!(v >= 0 && v < (double)n && v == floor(v)))
            return fail(r, "array 'id', point %zu: id %g is not in 0..%zu (the ids must be a "
                           "permutation of 0..n-1)",
                        k, v, n ? n - 1 : 0);
        size_t i = (size_t)v;
        if (row[i] != SIZE_MAX)
            return fail(r, "array 'id', point %zu: id %zu also at point %zu (the ids must be a "
                           "permutation of 0..n-1)",
                        k, i, row[i]);
        row[i] = k;
        part[k] = i;
    }
    return PST_OK;
}

static int build(reader *r, pst_cloud **out)
{
    size_t iV, ih;
    int st = check_arrays(r, &iV, &ih);
    if (st != PST_OK)
        return st;
    size_t n = (size_t)r->npoints;
    /* the sizes were bounded by the file before anything this large is allocated: every
     * decode checks its byte count against the data that is there, but the buffers come
     * first, so bound n by the file size (each value takes at least one byte of appended data,
     * or 2 characters of ascii / 4/3 of base64) */
    if (n > r->len)
        return fail(r, "the Piece declares %zu points, more than the file's %zu bytes can hold",
                    n, r->len);
    double *tmp = malloc((n ? n : 1) * 3 * sizeof *tmp);
    size_t *part = malloc((n ? n : 1) * sizeof *part), *row = malloc((n ? n : 1) * sizeof *row);
    pst_cloud *c = NULL;
    if (!tmp || !part || !row) {
        st = oom(r);
        goto done;
    }
    /* positions and the dimension */
    int dim = 2;
    if (n > 0) {
        if ((st = decode(r, &r->points, tmp)) != PST_OK ||
            (st = check_finite(r, &r->points, tmp)) != PST_OK)
            goto done;
        for (size_t k = 0; k < n && dim == 2; ++k)
            if (tmp[3 * k + 2] != 0)
                dim = 3;
    }
    double *pts = tmp;
    tmp = malloc((n ? n : 1) * 3 * sizeof *tmp);
    if (!tmp) {
        tmp = pts;
        st = oom(r);
        goto done;
    }
    if ((st = make_order(r, tmp, part, row)) != PST_OK) {
        free(pts);
        goto done;
    }
    if ((st = pst_cloud_create(&c, dim, n, NULL)) != PST_OK) {
        free(pts);
        st = st == PST_ENOMEM ? oom(r) : fail(r, "cannot create a cloud of %zu points", n);
        goto done;
    }
    for (size_t k = 0; k < n; ++k)
        for (int d = 0; d < dim; ++d)
            c->x[d][part[k]] = pts[3 * k + (size_t)d];
    free(pts);
    /* h: uniform when every value is the same (as the CSV reader) */
    if ((st = decode(r, &r->a[ih], tmp)) != PST_OK)
        goto done;
    int uniform = 1;
    for (size_t k = 1; k < n; ++k)
        uniform = uniform && tmp[k] == tmp[0];
    if (!uniform && !pst_cloud_h_per_particle(c)) {
        st = oom(r);
        goto done;
    }
    if ((st = store_array(r, c, &r->a[ih], tmp, part, 0)) != PST_OK)
        goto done;
    if (uniform && n > 0)
        pst_cloud_set_h_uniform(c, tmp[0], NULL);
    /* the others in file order */
    for (size_t k = 0; k < r->na; ++k) {
        vtu_in_array *a = &r->a[k];
        int role = role_of(a->name);
        if (k == ih || role == R_ID || role == R_STATUS)
            continue;
        size_t field = 0;
        char why[PST_ERRLEN] = "";
        if (role == R_MSCALAR || role == R_MDIAG)
            st = pst_cloud_set_mobility(c, role == R_MSCALAR ? 1 : dim, why);
        else if (role == R_FIELD) {
            double *data;
            st = pst_cloud_add_field(c, a->name, &data, why);
            field = c->nfields - 1;
        }
        if (st != PST_OK) {
            st = st == PST_ENOMEM ? oom(r) : fail_at(r, a->at, "array '%s': %s", a->name, why);
            goto done;
        }
        if ((st = decode(r, a, tmp)) != PST_OK || (st = store_array(r, c, a, tmp, part, field)))
            goto done;
    }
    (void)iV;
    size_t pa, pb;
    int dup = pst_cloud_find_duplicate(c, &pa, &pb);
    if (dup < 0) {
        st = oom(r);
    } else if (dup) {
        size_t ra = row[pa] < row[pb] ? row[pa] : row[pb], rb = row[pa] ^ row[pb] ^ ra;
        st = fail(r, "array 'Points', point %zu: duplicate particle: same coordinates as point "
                     "%zu",
                  rb, ra);
    }
done:
    free(tmp);
    free(part);
    free(row);
    if (st != PST_OK) {
        pst_cloud_destroy(c);
        c = NULL;
    }
    *out = c;
    return st;
}

/* Read the whole file, with a NUL after the last byte. */
static int slurp(const char *path, unsigned char **buf, size_t *len, char *err)
{
    *buf = NULL;
    *len = 0;
    FILE *f = fopen(path, "rb");
    if (!f) {
        pst_set_err(err, "%s: cannot open: %s", path, strerror(errno));
        return PST_EIO;
    }
    size_t cap = 1 << 16, n = 0;
    unsigned char *b = malloc(cap);
    while (b) {
        n += fread(b + n, 1, cap - 1 - n, f);
        if (n < cap - 1)
            break;
        unsigned char *nb = cap <= SIZE_MAX / 2 ? realloc(b, 2 * cap) : NULL;
        if (!nb) {
            free(b);
            b = NULL;
            break;
        }
        b = nb;
        cap *= 2;
    }
    int bad = ferror(f);
    int e = errno;
    fclose(f);
    if (!b) {
        pst_set_err(err, "%s: out of memory reading the file", path);
        return PST_ENOMEM;
    }
    if (bad) {
        free(b);
        pst_set_err(err, "%s: read error: %s", path, strerror(e));
        return PST_EIO;
    }
    b[n] = '\0';
    *buf = b;
    *len = n;
    return PST_OK;
}

int pst_cloud_read_vtu(pst_cloud **out, const char *path, char *err)
{
    *out = NULL;
    reader r;
    memset(&r, 0, sizeof r);
    r.path = path;
    r.err = err;
    unsigned char *buf;
    int st = slurp(path, &buf, &r.len, err);
    if (st != PST_OK)
        return st;
    r.buf = buf;
    st = scan_xml(&r);
    if (st == PST_OK)
        st = build(&r, out);
    for (size_t k = 0; k < r.na; ++k)
        free(r.a[k].text);
    free(r.a);
    free(r.points.text);
    free(buf);
    return st;
}
