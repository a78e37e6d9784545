/* What the parts of the VTU reader share (io_vtu_read.c is the entry point): the file in
 * memory with what the walk found in it, the DataArrays it keeps, and the steps that more than
 * one part calls. Private to the reader. */
#ifndef PSTENCIL_VTU_READ_H
#define PSTENCIL_VTU_READ_H

#include "cloud_layout.h"
#include "internal.h"

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

/* "FILE:LINE:COLUMN: message" for a place in the XML. */
int vtu_fail_at(reader *r, size_t off, const char *fmt, ...)
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
/* The file's bytes [at, at + len) equal the string s. */
int vtu_name_is(const reader *r, size_t at, size_t len, const char *s);
/* Skip to just after `end` (a NUL-free string); 0 when the file ends first. */
int vtu_skip_past(reader *r, const char *end);
/* Parse the tag at r->pos (a '<' that opens an element or an end tag). */
int vtu_parse_tag(reader *r, xtag *t);
/* Copy attribute `key` of `t` into out (cap bytes) with the five predefined entities decoded.
 * 1: found, 0: absent, -1: too long for out. */
int vtu_get_attr(const reader *r, const xtag *t, const char *key, char *out, size_t cap);
/* An attribute parsed as a non-negative decimal integer; 1 found, 0 absent, error otherwise. */
int vtu_get_uint(reader *r, const xtag *t, const char *key, uint64_t *v, uint64_t max);
/* Walk the XML: the root, the dataset element, the one Piece with its Points and PointData,
 * and the AppendedData element (where the scan stops). Everything else is skipped. */
int vtu_scan_xml(reader *r);
/* Decode array a (npoints * ncomp values) into out. */
int vtu_decode(reader *r, vtu_in_array *a, double *out);

#endif
