/* What the parts of the VTU reader share (io_vtu_read.c is the entry point): the file in
 * memory with what the walk found in it, the DataArrays it keeps, and the steps that more than
 * one part calls. Private to the reader. */
#ifndef PSTENCIL_VTU_READ_H
#define PSTENCIL_VTU_READ_H

#include "cloud_layout.h"
#include "internal.h"

#include <expat.h>
#include <stddef.h>
#include <stdint.h>

enum { FMT_APPENDED, FMT_ASCII, FMT_BINARY };
enum { SEC_POINTDATA, SEC_POINTS };

/* The scalar types of VTK's XML format that the reader converts to double. */
typedef struct {
    const char *name;
    int size, is_float, is_signed;
} vtk_type;
enum { NTYPES = 10 };
extern const vtk_type vtk_types[NTYPES];

#define MAX_DEPTH 64
/* deflate expands at most 1032 times (a 258-byte match in 2 bits): what a compressed block of
 * c bytes can hold, so that sizes from a file are capped before anything is allocated */
#define VTU_ZLIB_MAX_RATIO 1032
#define NAME_CAP 256

/* A place in the XML: 1-based line and column. */
typedef struct {
    unsigned long line, col;
} vtu_pos;

/* One DataArray of the Points or PointData of the Piece. */
typedef struct {
    char name[NAME_CAP];
    vtu_pos at;         /* its start tag */
    int sec, type, ncomp, format;
    uint64_t offset;    /* appended: into the block after '_' */
    char *text;         /* inline (ascii, binary): the element's own text, NUL-terminated */
    size_t text_len, text_cap;
} vtu_in_array;

typedef struct {
    const char *path;
    char *err;
    const unsigned char *buf; /* the file, with a NUL after the last byte */
    size_t len;
    XML_Parser xp;            /* while the XML is parsed: where its events are */
    /* from the header */
    int big_endian, header_size, compressed, have_piece, have_points;
    uint64_t npoints;
    /* the appended block: [data, data_end) of buf */
    int have_appended, appended_b64;
    size_t data, data_end;
    /* the arrays */
    vtu_in_array *a;
    size_t na, cap;
    vtu_in_array points;
} reader;

/* "FILE:LINE:COLUMN: message" for a place in the XML. */
int vtu_fail_at(reader *r, vtu_pos at, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* "FILE: message" (values, appended data). */
int vtu_fail(reader *r, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* "FILE: out of memory", PST_ENOMEM. */
int vtu_oom(reader *r);
/* XML white space. */
static inline int vtu_is_space(int ch)
{
    return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r';
}
/* Where the parser is: the event being reported (a start tag, text). */
vtu_pos vtu_here(const reader *r);
/* Attribute `key` of an expat attribute list (name, value pairs), or NULL. */
const char *vtu_attr(const XML_Char **atts, const char *key);
/* An attribute parsed as a non-negative decimal integer; 1 found, 0 absent, error otherwise. */
int vtu_get_uint(reader *r, const XML_Char **atts, const char *key, uint64_t *v, uint64_t max);
/* After the start tag of <AppendedData> that ends at byte `tag_end`: the block from after its
 * '_' to the last </AppendedData> of the file. */
int vtu_locate_appended(reader *r, size_t tag_end, vtu_pos at);
/* Walk the XML with expat: the root, the dataset element, the one Piece with its Points and
 * PointData, and the AppendedData element (where the parse stops). Everything else is
 * skipped. */
int vtu_scan_xml(reader *r);

/* ---- fields ------------------------------------------------------------------------------ */
/* The components of an array of ncomp (1, 3 or 6) components that become fields in dim
 * dimensions, in field order (comp[j] indexes the array's components); their count. */
int vtu_field_parts(int ncomp, int dim, int comp[6]);
/* The field names of the field arrays (in file order, each split into its components),
 * checked: valid names, at most PST_MAX_FIELDS, no name twice. *names is malloc'ed. */
int vtu_field_names(reader *r, int dim, vtu_in_array *const *arrays, size_t na,
                    char (**names)[PST_MAX_NAME], size_t *count);
/* Store field array a (values v, file row k -> particle part[k]) into the fields from
 * `field` on; in 2D the dropped components must be 0. */
int vtu_store_field(reader *r, pst_cloud *c, const vtu_in_array *a, const double *v,
                    const size_t *part, size_t field);

/* ---- decoding ---------------------------------------------------------------------------- */
/* An unsigned integer of `size` bytes at p in the file's byte order. */
uint64_t vtu_load_uint(const unsigned char *p, int size, int big);
/* Convert count values of array a's type at p to doubles. */
void vtu_convert(const reader *r, const vtu_in_array *a, const unsigned char *p, double *out,
                 size_t count);
/* The declared byte count of an array: n * ncomp * size. */
uint64_t vtu_expect_bytes(const reader *r, const vtu_in_array *a);
/* Decode base64 in place (padding may end any quantum); the byte count, or -1 at a bad
 * character (its index in *bad). */
long long vtu_b64_decode(char *s, size_t len, size_t *bad);
/* A base64 stream in the appended block, decoded on demand (bytes of a quantum that the
 * caller did not take yet wait in pend). */
typedef struct {
    const unsigned char *s;
    size_t len, pos;
    unsigned char pend[3];
    int npend;
} vtu_b64_stream;
/* Take up to `want` bytes; returns how many were produced (fewer at the end of the block or at
 * a character that is not base64, padding or white space). */
size_t vtu_b64_take(vtu_b64_stream *b, unsigned char *out, size_t want);
/* Where the bytes of an array come from: raw bytes [p, p + len), or a base64 stream (b64 not
 * NULL). */
typedef struct {
    const unsigned char *p;
    size_t len, pos;
    vtu_b64_stream *b64;
} vtu_source;
/* A zlib-compressed array (vtkZLibDataCompressor) read from src into out. */
int vtu_decode_zlib(reader *r, const vtu_in_array *a, vtu_source *src, double *out);
/* Decode array a (npoints * ncomp values) into out. */
int vtu_decode(reader *r, vtu_in_array *a, double *out);

#endif
