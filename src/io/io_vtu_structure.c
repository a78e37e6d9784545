/* The structure of a VTU file, walked with expat: the root, the dataset, the one Piece with its
 * Points and PointData arrays, and the AppendedData element, where the parse stops. Everything
 * else is skipped. */
#include "vtu_read.h"

#include "check.h"

#include <stdlib.h>
#include <string.h>

enum { E_OTHER, E_VTKFILE, E_DATASET, E_PIECE, E_POINTDATA, E_POINTS, E_ARRAY, E_SKIP };

/* The elements open on the way down, and what the walk has seen so far. */
typedef struct {
    reader *r;
    int st;            /* the first error of a handler (its message is in r->err) */
    int kind[MAX_DEPTH];
    vtu_pos open_at[MAX_DEPTH];
    char open_name[MAX_DEPTH][16]; /* for the messages (truncated) */
    int depth, npieces, stopped;
    char dataset[32];
    vtu_in_array *inl; /* the inline array whose text is being collected */
} xml_walk;

/* Stop the parse with the status of a failed step. */
static void stop_with(xml_walk *w, int st)
{
    if (st == PST_OK)
        return;
    w->st = st;
    XML_StopParser(w->r->xp, XML_FALSE);
}

/* <VTKFile ...>: dataset type, byte order, header type, compressor. */
static int root_tag(reader *r, const char *name, const XML_Char **atts, char *dataset,
                    size_t cap)
{
    vtu_pos at = vtu_here(r);
    if (strcmp(name, "VTKFile"))
        return vtu_fail_at(r, at, "not a VTK XML file: the root element is <%.64s>, not "
                           "<VTKFile>", name);
    const char *s = vtu_attr(atts, "type");
    if (!s || (strcmp(s, "UnstructuredGrid") && strcmp(s, "PolyData")))
        return vtu_fail_at(r, at,
                           "unsupported dataset type \"%.64s\" (UnstructuredGrid or "
                           "PolyData)",
                           s ? s : "");
    snprintf(dataset, cap, "%s", s);
    s = vtu_attr(atts, "compressor");
    if (s && !strcmp(s, "vtkZLibDataCompressor"))
        r->compressed = 1;
    else if (s && s[0])
        return vtu_fail_at(r, at,
                           "compressor \"%.64s\" is not supported: only vtkZLibDataCompressor "
                           "(zlib) or none (e.g. ParaView: Save Data, compressor ZLib or None)",
                           s);
    s = vtu_attr(atts, "byte_order");
    if (s && !strcmp(s, "BigEndian"))
        r->big_endian = 1;
    else if (s && strcmp(s, "LittleEndian"))
        return vtu_fail_at(r, at, "unknown byte_order (LittleEndian or BigEndian)");
    s = vtu_attr(atts, "header_type");
    r->header_size = 4; /* VTK's default (file version 0.1) */
    if (s && !strcmp(s, "UInt64"))
        r->header_size = 8;
    else if (s && strcmp(s, "UInt32"))
        return vtu_fail_at(r, at, "unsupported header_type \"%.32s\" (UInt32 or UInt64)", s);
    return PST_OK;
}

/* The array of a <DataArray> tag of the Points or the PointData, zeroed. */
static int new_array(reader *r, int sec, vtu_in_array **out)
{
    vtu_in_array *a;
    if (sec == SEC_POINTS) {
        if (r->have_points)
            return vtu_fail_at(r, vtu_here(r), "<Points> holds more than one DataArray");
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
    a->at = vtu_here(r);
    a->sec = sec;
    *out = a;
    return PST_OK;
}

/* The format of a DataArray, and the offset of an appended one. */
static int array_format(reader *r, const XML_Char **atts, vtu_in_array *a)
{
    const char *s = vtu_attr(atts, "format");
    if (s && !strcmp(s, "appended"))
        a->format = FMT_APPENDED;
    else if (s && !strcmp(s, "ascii"))
        a->format = FMT_ASCII;
    else if (s && !strcmp(s, "binary"))
        a->format = FMT_BINARY;
    else
        return vtu_fail_at(r, a->at, "array '%.64s': format must be appended, binary or ascii",
                           a->name);
    if (a->format == FMT_APPENDED) {
        int got = vtu_get_uint(r, atts, "offset", &a->offset, UINT64_MAX);
        if (got < 0)
            return PST_EINPUT;
        if (got == 0)
            return vtu_fail_at(r, a->at, "array '%.64s': format=\"appended\" without an offset",
                               a->name);
    }
    return PST_OK;
}

/* <DataArray ...> of the Points or the PointData. */
static int array_tag(reader *r, const XML_Char **atts, int sec, vtu_in_array **out)
{
    vtu_in_array *a = NULL;
    PST_TRY(new_array(r, sec, &a));
    const char *s = vtu_attr(atts, "Name");
    if (s && strlen(s) >= NAME_CAP)
        return vtu_fail_at(r, a->at, "DataArray name longer than %d characters", NAME_CAP - 1);
    if (!s && sec == SEC_POINTDATA)
        return vtu_fail_at(r, a->at, "PointData DataArray without a Name");
    snprintf(a->name, sizeof a->name, "%s", s ? s : "Points");
    s = vtu_attr(atts, "type");
    a->type = -1;
    for (size_t k = 0; s && k < NTYPES; ++k)
        if (!strcmp(s, vtk_types[k].name))
            a->type = (int)k;
    if (a->type < 0)
        return vtu_fail_at(r, a->at,
                           "array '%.64s': unsupported type \"%.32s\" (Float64, Float32, "
                           "Int8..Int64, UInt8..UInt64)",
                           a->name, s ? s : "");
    uint64_t v = 1;
    int got = vtu_get_uint(r, atts, "NumberOfComponents", &v, 1024);
    if (got < 0)
        return PST_EINPUT;
    if (v < 1)
        return vtu_fail_at(r, a->at, "array '%.64s': NumberOfComponents must be >= 1", a->name);
    a->ncomp = (int)v;
    PST_TRY(array_format(r, atts, a));
    got = vtu_get_uint(r, atts, "NumberOfTuples", &v, UINT64_MAX);
    if (got < 0)
        return PST_EINPUT;
    if (got > 0 && v != r->npoints)
        return vtu_fail_at(r, a->at,
                           "array '%.64s' has NumberOfTuples=%llu but the piece has %llu "
                           "points",
                           a->name, (unsigned long long)v, (unsigned long long)r->npoints);
    *out = a;
    return PST_OK;
}

/* <AppendedData>: its encoding; the parse stops here, because what follows the '_' is raw
 * bytes, not XML (expat would refuse them), and the block is located by hand. */
static int appended_tag(reader *r, const XML_Char **atts, int depth)
{
    vtu_pos at = vtu_here(r);
    const char *enc = vtu_attr(atts, "encoding");
    if (enc && !strcmp(enc, "base64"))
        r->appended_b64 = 1;
    else if (!enc || strcmp(enc, "raw"))
        return vtu_fail_at(r, at, "AppendedData encoding \"%.31s\" is not supported (raw or "
                           "base64)", enc ? enc : "");
    if (depth != 1)
        return vtu_fail_at(r, at, "malformed XML: <AppendedData> inside an element");
    size_t tag_end = (size_t)XML_GetCurrentByteIndex(r->xp) +
                     (size_t)XML_GetCurrentByteCount(r->xp);
    return vtu_locate_appended(r, tag_end, at);
}

/* <Piece>: the only one, with its NumberOfPoints. */
static int piece_tag(reader *r, const XML_Char **atts, xml_walk *w)
{
    if (++w->npieces > 1)
        return vtu_fail_at(r, vtu_here(r),
                           "more than one Piece: only single-piece files are supported");
    int got = vtu_get_uint(r, atts, "NumberOfPoints", &r->npoints, UINT32_MAX);
    if (got < 0)
        return PST_EINPUT;
    if (got == 0)
        return vtu_fail_at(r, vtu_here(r), "Piece without NumberOfPoints");
    r->have_piece = 1;
    return PST_OK;
}

/* What a start tag below the root is (E_SKIP for what the reader does not need). */
static int element_kind(xml_walk *w, const char *name, const XML_Char **atts, int *k)
{
    reader *r = w->r;
    int parent = w->kind[w->depth - 1];
    *k = E_SKIP;
    if (parent == E_VTKFILE && !strcmp(name, w->dataset))
        *k = E_DATASET;
    else if (parent == E_DATASET && !strcmp(name, "Piece"))
        *k = E_PIECE;
    else if (parent == E_PIECE && !strcmp(name, "PointData"))
        *k = E_POINTDATA;
    else if (parent == E_PIECE && !strcmp(name, "Points"))
        *k = E_POINTS;
    else if ((parent == E_POINTDATA || parent == E_POINTS) && !strcmp(name, "DataArray"))
        *k = E_ARRAY;
    if (*k == E_PIECE)
        return piece_tag(r, atts, w);
    if (*k != E_ARRAY)
        return PST_OK;
    vtu_in_array *a = NULL;
    PST_TRY(array_tag(r, atts, parent == E_POINTS ? SEC_POINTS : SEC_POINTDATA, &a));
    if (a->format != FMT_APPENDED) {
        a->text = malloc(1); /* an empty element has empty text */
        if (!a->text)
            return vtu_oom(r);
        a->text[0] = '\0';
        a->text_cap = 1;
        w->inl = a;
    }
    return PST_OK;
}

static void XMLCALL on_start(void *data, const XML_Char *name, const XML_Char **atts)
{
    xml_walk *w = data;
    reader *r = w->r;
    if (w->st != PST_OK || w->stopped)
        return;
    if (w->depth == MAX_DEPTH) {
        stop_with(w, vtu_fail_at(r, vtu_here(r), "malformed XML: elements nested deeper than "
                                 "%d", MAX_DEPTH));
        return;
    }
    int k = E_SKIP, st;
    if (w->depth == 0) {
        st = root_tag(r, name, atts, w->dataset, sizeof w->dataset);
        k = E_VTKFILE;
    } else if (w->kind[w->depth - 1] == E_VTKFILE && !strcmp(name, "AppendedData")) {
        st = appended_tag(r, atts, w->depth);
        w->stopped = st == PST_OK;
        XML_StopParser(r->xp, XML_FALSE);
    } else {
        st = element_kind(w, name, atts, &k);
    }
    stop_with(w, st);
    if (st != PST_OK || w->stopped)
        return;
    w->kind[w->depth] = k;
    w->open_at[w->depth] = vtu_here(r);
    snprintf(w->open_name[w->depth], sizeof w->open_name[w->depth], "%s", name);
    ++w->depth;
}

static void XMLCALL on_end(void *data, const XML_Char *name)
{
    (void)name; /* expat checks that it closes the innermost element */
    xml_walk *w = data;
    if (w->st != PST_OK || w->stopped || w->depth == 0)
        return;
    if (w->kind[w->depth - 1] == E_ARRAY)
        w->inl = NULL;
    --w->depth;
}

/* The text of an inline array (only its own: not that of child elements). */
static void XMLCALL on_text(void *data, const XML_Char *s, int len)
{
    xml_walk *w = data;
    if (w->st != PST_OK || w->stopped || !w->inl || w->kind[w->depth - 1] != E_ARRAY ||
        len <= 0)
        return;
    vtu_in_array *a = w->inl;
    size_t need = a->text_len + (size_t)len + 1;
    if (need > a->text_cap) {
        size_t cap = 2 * a->text_cap > need ? 2 * a->text_cap : need;
        char *t = realloc(a->text, cap);
        if (!t) {
            stop_with(w, vtu_oom(w->r));
            return;
        }
        a->text = t;
        a->text_cap = cap;
    }
    memcpy(a->text + a->text_len, s, (size_t)len);
    a->text_len += (size_t)len;
    a->text[a->text_len] = '\0';
}

/* A DTD could define entities that expand without bound; VTK never writes one. */
static void XMLCALL on_doctype(void *data, const XML_Char *name, const XML_Char *sysid,
                               const XML_Char *pubid, int has_internal_subset)
{
    (void)name, (void)sysid, (void)pubid, (void)has_internal_subset;
    xml_walk *w = data;
    stop_with(w, vtu_fail_at(w->r, vtu_here(w->r), "<!DOCTYPE> is not supported in a VTU "
                             "file"));
}

/* expat's own error, with the element it happened in. */
static int xml_error(reader *r, const xml_walk *w)
{
    enum XML_Error e = XML_GetErrorCode(r->xp);
    int d = w->depth;
    if (d > 0 && (e == XML_ERROR_NO_ELEMENTS || e == XML_ERROR_UNCLOSED_TOKEN ||
                  e == XML_ERROR_PARTIAL_CHAR) &&
        (size_t)XML_GetCurrentByteIndex(r->xp) >= r->len)
        return vtu_fail_at(r, w->open_at[d - 1], "truncated file: <%s> is not closed",
                           w->open_name[d - 1]);
    if (d == 0 && e == XML_ERROR_NO_ELEMENTS)
        return vtu_fail(r, "not a VTK XML file: no <VTKFile> element");
    if (d > 0 && e == XML_ERROR_TAG_MISMATCH)
        return vtu_fail_at(r, vtu_here(r), "malformed XML: mismatched tag: this end tag does "
                           "not close <%s> of %lu:%lu", w->open_name[d - 1],
                           w->open_at[d - 1].line, w->open_at[d - 1].col);
    /* the character expat stopped at, when it is one to print */
    size_t at = (size_t)XML_GetCurrentByteIndex(r->xp);
    char what[16] = "";
    if (at < r->len && r->buf[at] > 32 && r->buf[at] < 127)
        snprintf(what, sizeof what, " at '%c'", r->buf[at]);
    if (d > 0)
        return vtu_fail_at(r, vtu_here(r), "malformed XML: %s%s (inside <%s> of line %lu)",
                           XML_ErrorString(e), what, w->open_name[d - 1],
                           w->open_at[d - 1].line);
    return vtu_fail_at(r, vtu_here(r), "malformed XML: %s%s", XML_ErrorString(e), what);
}

/* What the walk must have found by its end. */
static int check_found(reader *r, const xml_walk *w)
{
    if (!r->have_piece)
        return vtu_fail(r, "no <Piece> in the <%s>", w->dataset);
    if (!r->have_points && r->npoints > 0)
        return vtu_fail(r, "the Piece has %llu points but no <Points> array",
                        (unsigned long long)r->npoints);
    return PST_OK;
}

int vtu_scan_xml(reader *r)
{
    xml_walk w = {.r = r, .st = PST_OK};
    r->xp = XML_ParserCreate(NULL);
    if (!r->xp)
        return vtu_oom(r);
    XML_SetUserData(r->xp, &w);
    XML_SetElementHandler(r->xp, on_start, on_end);
    XML_SetCharacterDataHandler(r->xp, on_text);
    XML_SetStartDoctypeDeclHandler(r->xp, on_doctype);
    /* XML_Parse takes an int length: files beyond 1 GiB go in pieces */
    enum XML_Status xs = XML_STATUS_OK;
    const size_t piece = (size_t)1 << 30;
    for (size_t at = 0; xs == XML_STATUS_OK && (at < r->len || at == 0);) {
        size_t n = r->len - at < piece ? r->len - at : piece;
        xs = XML_Parse(r->xp, (const char *)r->buf + at, (int)n, at + n == r->len);
        at += n;
        if (at == r->len)
            break;
    }
    int st = w.st;
    if (st == PST_OK && xs != XML_STATUS_OK && !w.stopped)
        st = xml_error(r, &w);
    XML_ParserFree(r->xp);
    r->xp = NULL;
    return st == PST_OK ? check_found(r, &w) : st;
}
