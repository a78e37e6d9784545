/* The structure of a VTU file: the root, the dataset, the one Piece with its Points and
 * PointData arrays, and the AppendedData block, where the walk stops. Everything else is
 * skipped. */
#include "vtu_read.h"

#include "check.h"

#include <stdlib.h>
#include <string.h>

enum { E_OTHER, E_VTKFILE, E_DATASET, E_PIECE, E_POINTDATA, E_POINTS, E_ARRAY, E_SKIP };

/* <VTKFile ...>: dataset type, byte order, header type, compressor. */
static int root_tag(reader *r, const xtag *t, char *dataset, size_t cap)
{
    char s[64];
    if (!vtu_name_is(r, t->name, t->name_len, "VTKFile"))
        return vtu_fail_at(
            r, t->at, "not a VTK XML file: the root element is <%.*s>, not <VTKFile>",
            (int)(t->name_len < 64 ? t->name_len : 64), (const char *)r->buf + t->name);
    int got = vtu_get_attr(r, t, "type", dataset, cap);
    if (got <= 0 || (strcmp(dataset, "UnstructuredGrid") && strcmp(dataset, "PolyData")))
        return vtu_fail_at(r, t->at,
                           "unsupported dataset type \"%.64s\" (UnstructuredGrid or "
                           "PolyData)",
                           got > 0 ? dataset : "");
    got = vtu_get_attr(r, t, "compressor", s, sizeof s);
    if (got != 0 && !(got > 0 && s[0] == '\0'))
        return vtu_fail_at(r, t->at,
                           "compressed VTU is not supported: write it uncompressed (e.g. "
                           "ParaView: Save Data, uncheck compression)");
    got = vtu_get_attr(r, t, "byte_order", s, sizeof s);
    if (got > 0 && !strcmp(s, "BigEndian"))
        r->big_endian = 1;
    else if (got != 0 && !(got > 0 && !strcmp(s, "LittleEndian")))
        return vtu_fail_at(r, t->at, "unknown byte_order (LittleEndian or BigEndian)");
    got = vtu_get_attr(r, t, "header_type", s, sizeof s);
    r->header_size = 4; /* VTK's default (file version 0.1) */
    if (got > 0 && !strcmp(s, "UInt64"))
        r->header_size = 8;
    else if (got != 0 && !(got > 0 && !strcmp(s, "UInt32")))
        return vtu_fail_at(r, t->at, "unsupported header_type \"%.32s\" (UInt32 or UInt64)",
                           got > 0 ? s : "");
    return PST_OK;
}

/* <DataArray ...> of the Points or the PointData. */
static int array_tag(reader *r, const xtag *t, int sec, vtu_in_array **out)
{
    vtu_in_array *a;
    if (sec == SEC_POINTS) {
        if (r->have_points)
            return vtu_fail_at(r, t->at, "<Points> holds more than one DataArray");
        r->have_points = 1;
        a = &r->points;
    } else {
        if (r->na == r->cap) {
            size_t cap = r->cap ? 2 * r->cap : 16;
            vtu_in_array *na = realloc(r->a, cap * sizeof *na);
            if (!na)
                return vtu_oom(r);
            r->a = na;
            r->cap = cap;
        }
        a = &r->a[r->na++];
    }
    memset(a, 0, sizeof *a);
    a->at = t->at;
    a->sec = sec;
    int got = vtu_get_attr(r, t, "Name", a->name, sizeof a->name);
    if (got < 0)
        return vtu_fail_at(r, t->at, "DataArray name longer than %d characters", NAME_CAP - 1);
    if (got == 0 && sec == SEC_POINTDATA)
        return vtu_fail_at(r, t->at, "PointData DataArray without a Name");
    if (got == 0)
        strcpy(a->name, "Points");
    char s[32];
    got = vtu_get_attr(r, t, "type", s, sizeof s);
    a->type = -1;
    for (size_t k = 0; got > 0 && k < NTYPES; ++k)
        if (!strcmp(s, vtk_types[k].name))
            a->type = (int)k;
    if (a->type < 0)
        return vtu_fail_at(r, t->at,
                           "array '%.64s': unsupported type \"%.32s\" (Float64, Float32, "
                           "Int8..Int64, UInt8..UInt64)",
                           a->name, got > 0 ? s : "");
    uint64_t v = 1;
    got = vtu_get_uint(r, t, "NumberOfComponents", &v, 1024);
    if (got < 0)
        return PST_EINPUT;
    if (v < 1)
        return vtu_fail_at(r, t->at, "array '%.64s': NumberOfComponents must be >= 1", a->name);
    a->ncomp = (int)v;
    got = vtu_get_attr(r, t, "format", s, sizeof s);
    if (got > 0 && !strcmp(s, "appended"))
        a->format = FMT_APPENDED;
    else if (got > 0 && !strcmp(s, "ascii"))
        a->format = FMT_ASCII;
    else if (got > 0 && !strcmp(s, "binary"))
        a->format = FMT_BINARY;
    else
        return vtu_fail_at(r, t->at, "array '%.64s': format must be appended, binary or ascii",
                           a->name);
    if (a->format == FMT_APPENDED) {
        got = vtu_get_uint(r, t, "offset", &a->offset, UINT64_MAX);
        if (got < 0)
            return PST_EINPUT;
        if (got == 0)
            return vtu_fail_at(r, t->at, "array '%.64s': format=\"appended\" without an offset",
                               a->name);
    }
    got = vtu_get_uint(r, t, "NumberOfTuples", &v, UINT64_MAX);
    if (got < 0)
        return PST_EINPUT;
    if (got > 0 && v != r->npoints)
        return vtu_fail_at(r, t->at,
                           "array '%.64s' has NumberOfTuples=%llu but the piece has %llu "
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
        return vtu_oom(r);
    memcpy(s + a->text_len, r->buf + from, to - from);
    a->text = s;
    a->text_len += to - from;
    s[a->text_len] = '\0';
    return PST_OK;
}

/* The elements open on the way down, and what the walk has seen so far. */
typedef struct {
    int kind[MAX_DEPTH];
    size_t open_at[MAX_DEPTH], open_name[MAX_DEPTH], open_len[MAX_DEPTH];
    int depth, done, npieces;
    char dataset[32];
    vtu_in_array *inl; /* the inline array whose text is being collected */
} xml_walk;

/* Comments, processing instructions and declarations at `at`: skipped (*skipped = 1). */
static int skip_markup(reader *r, size_t at, int *skipped)
{
    const char *p = (const char *)r->buf + at;
    size_t left = r->len - at;
    *skipped = 1;
    if (left >= 4 && !memcmp(p, "<!--", 4))
        return vtu_skip_past(r, "-->") ? PST_OK
                                       : vtu_fail_at(r, at, "truncated file: unterminated comment");
    if (left >= 2 && (p[1] == '?' || p[1] == '!')) {
        if (left >= 9 && !memcmp(p, "<![CDATA[", 9))
            return vtu_fail_at(r, at, "CDATA sections are not supported");
        if (!vtu_skip_past(r, p[1] == '?' ? "?>" : ">"))
            return vtu_fail_at(r, at, "truncated file: unterminated <%c", p[1]);
        return PST_OK;
    }
    *skipped = 0;
    return PST_OK;
}

/* <AppendedData>: its encoding, and the block from after its '_' to the last
 * </AppendedData> of the file. */
static int appended_tag(reader *r, const xtag *t, int depth)
{
    char enc[32];
    int got = vtu_get_attr(r, t, "encoding", enc, sizeof enc);
    if (got > 0 && !strcmp(enc, "base64"))
        r->appended_b64 = 1;
    else if (got <= 0 || strcmp(enc, "raw"))
        return vtu_fail_at(r, t->at,
                           "AppendedData encoding \"%.31s\" is not supported "
                           "(raw or base64)",
                           got > 0 ? enc : "");
    size_t q = r->pos;
    while (q < r->len && vtu_is_space(r->buf[q]))
        ++q;
    if (t->empty || q >= r->len || r->buf[q] != '_')
        return vtu_fail_at(r, q, "AppendedData does not start with '_'");
    r->have_appended = 1;
    r->data = q + 1;
    static const char end_tag[] = "</AppendedData>";
    size_t m = sizeof end_tag - 1;
    r->data_end = 0;
    for (size_t e = r->len; e >= r->data + m; --e)
        if (!memcmp(r->buf + e - m, end_tag, m)) {
            r->data_end = e - m;
            break;
        }
    if (r->data_end < r->data)
        return vtu_fail(r,
                        "truncated file: no </AppendedData> after the appended data "
                        "(which starts at byte %zu)",
                        r->data);
    if (depth != 1)
        return vtu_fail_at(r, t->at, "malformed XML: <AppendedData> inside an element");
    return PST_OK;
}

/* <Piece>: the only one, with its NumberOfPoints. */
static int piece_tag(reader *r, const xtag *t, xml_walk *w)
{
    if (++w->npieces > 1)
        return vtu_fail_at(r, t->at,
                           "more than one Piece: only single-piece files are "
                           "supported");
    int got = vtu_get_uint(r, t, "NumberOfPoints", &r->npoints, UINT32_MAX);
    if (got < 0)
        return PST_EINPUT;
    if (got == 0)
        return vtu_fail_at(r, t->at, "Piece without NumberOfPoints");
    r->have_piece = 1;
    return PST_OK;
}

/* <DataArray> of the Points or the PointData; an inline one starts collecting its text. */
static int data_array_tag(reader *r, const xtag *t, int parent, xml_walk *w)
{
    vtu_in_array *a = NULL;
    PST_TRY(array_tag(r, t, parent == E_POINTS ? SEC_POINTS : SEC_POINTDATA, &a));
    if (a->format != FMT_APPENDED) {
        a->text = malloc(1); /* an empty element has empty text */
        if (!a->text)
            return vtu_oom(r);
        a->text[0] = '\0';
        w->inl = a;
    }
    return PST_OK;
}

/* What a start tag below the root is (E_SKIP for what the reader does not need). */
static int element_kind(reader *r, const xtag *t, xml_walk *w, int *k)
{
    int parent = w->kind[w->depth - 1];
    *k = E_SKIP;
    if (parent == E_VTKFILE && vtu_name_is(r, t->name, t->name_len, w->dataset))
        *k = E_DATASET;
    else if (parent == E_DATASET && vtu_name_is(r, t->name, t->name_len, "Piece"))
        *k = E_PIECE;
    else if (parent == E_PIECE && vtu_name_is(r, t->name, t->name_len, "PointData"))
        *k = E_POINTDATA;
    else if (parent == E_PIECE && vtu_name_is(r, t->name, t->name_len, "Points"))
        *k = E_POINTS;
    else if ((parent == E_POINTDATA || parent == E_POINTS) &&
             vtu_name_is(r, t->name, t->name_len, "DataArray"))
        *k = E_ARRAY;
    if (*k == E_PIECE)
        return piece_tag(r, t, w);
    if (*k == E_ARRAY)
        return data_array_tag(r, t, parent, w);
    return PST_OK;
}

/* An end tag: it must close the innermost open element. */
static int end_tag(reader *r, const xtag *t, xml_walk *w)
{
    int d = w->depth;
    if (d == 0 || w->open_len[d - 1] != t->name_len ||
        memcmp(r->buf + t->name, r->buf + w->open_name[d - 1], t->name_len) != 0)
        return vtu_fail_at(r, t->at, "malformed XML: unexpected end tag </%.*s>",
                           (int)(t->name_len < 64 ? t->name_len : 64),
                           (const char *)r->buf + t->name);
    if (w->kind[d - 1] == E_ARRAY)
        w->inl = NULL;
    --w->depth;
    w->done = w->depth == 0;
    return PST_OK;
}

/* A start tag: classified and, unless empty, opened. *stop = 1 at <AppendedData>. */
static int start_tag(reader *r, const xtag *t, xml_walk *w, int *stop)
{
    if (w->depth == MAX_DEPTH)
        return vtu_fail_at(r, t->at, "malformed XML: elements nested deeper than %d", MAX_DEPTH);
    int k;
    if (w->depth == 0) {
        PST_TRY(root_tag(r, t, w->dataset, sizeof w->dataset));
        k = E_VTKFILE;
    } else if (w->kind[w->depth - 1] == E_VTKFILE &&
               vtu_name_is(r, t->name, t->name_len, "AppendedData")) {
        *stop = 1;
        return appended_tag(r, t, w->depth);
    } else {
        PST_TRY(element_kind(r, t, w, &k));
    }
    if (t->empty) {
        if (k == E_ARRAY)
            w->inl = NULL;
        if (w->depth == 0)
            return vtu_fail_at(r, t->at, "empty <VTKFile/>: no dataset");
        return PST_OK;
    }
    w->kind[w->depth] = k;
    w->open_at[w->depth] = t->at;
    w->open_name[w->depth] = t->name;
    w->open_len[w->depth] = t->name_len;
    ++w->depth;
    return PST_OK;
}

/* What the walk must have found by its end. */
static int check_found(reader *r, const xml_walk *w)
{
    int d = w->depth;
    if (d > 0 && !r->have_appended)
        return vtu_fail_at(r, w->open_at[d - 1], "truncated file: <%.*s> is not closed",
                           (int)(w->open_len[d - 1] < 64 ? w->open_len[d - 1] : 64),
                           (const char *)r->buf + w->open_name[d - 1]);
    if (!w->done && !r->have_appended)
        return vtu_fail(r, "not a VTK XML file: no <VTKFile> element");
    if (!r->have_piece)
        return vtu_fail(r, "no <Piece> in the <%s>", w->dataset);
    if (!r->have_points && r->npoints > 0)
        return vtu_fail(r, "the Piece has %llu points but no <Points> array",
                        (unsigned long long)r->npoints);
    return PST_OK;
}

int vtu_scan_xml(reader *r)
{
    xml_walk w = {.depth = 0};
    r->pos = 0;
    if (r->len >= 3 && !memcmp(r->buf, "\xEF\xBB\xBF", 3))
        r->pos = 3;
    for (int stop = 0; !stop;) {
        size_t text = r->pos;
        const unsigned char *lt = memchr(r->buf + r->pos, '<', r->len - r->pos);
        size_t at = lt ? (size_t)(lt - r->buf) : r->len;
        if (w.inl && w.depth > 0 && w.kind[w.depth - 1] == E_ARRAY)
            PST_TRY(add_text(r, w.inl, text, at));
        if (!lt)
            break;
        r->pos = at;
        int skipped;
        PST_TRY(skip_markup(r, at, &skipped));
        if (skipped)
            continue;
        if (w.done)
            return vtu_fail_at(r, at, "malformed XML: content after </VTKFile>");
        xtag t;
        PST_TRY(vtu_parse_tag(r, &t));
        PST_TRY(t.closing ? end_tag(r, &t, &w) : start_tag(r, &t, &w, &stop));
    }
    return check_found(r, &w);
}
