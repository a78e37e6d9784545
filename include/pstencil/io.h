/* pstencil: Reading and writing clouds (CSV and VTU) and the CSV tokenizer they and the sweep
 * results share. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_IO_H
#define PSTENCIL_PUBLIC_IO_H

#include "pstencil/cloud.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* --- CSV tokenizer ------------------------------------------------------------------------ */

/* One tokenizer for every CSV file (docs/io.md): RFC 4180 records (cells split by commas,
 * "quoted" cells may hold commas, doubled quotes and newlines), LF or CRLF line ends, a UTF-8
 * byte-order mark skipped. The first record is the header; every later record must have its
 * number of cells. Messages name "PATH:LINE:COLUMN", COLUMN the 1-based cell number and LINE
 * the record's first line. Caps on what a file may ask for, each with its own message: */
enum {
    PST_CSV_MAX_RECORD = 1 << 24, /* bytes of one record (its lines, quoted newlines included) */
    PST_CSV_MAX_CELLS = 1 << 16,  /* cells of one record                                       */
    PST_CSV_MAX_ROWS = 1 << 21    /* data rows of a pst_csv_table (clouds stream: see below)    */
};

/* Flags of a reader: trim spaces and tabs around each cell (quoted cells: outside the quotes),
 * skip lines holding only spaces and tabs (they still count for LINE). */
enum { PST_CSV_TRIM = 1, PST_CSV_SKIP_BLANK = 2 };

/* A streaming reader: one record at a time, so that a cloud of any size reads in the memory
 * of one line. */
typedef struct pst_csv_reader pst_csv_reader;

/* Open `path` (or, for pst_csv_open_text, read `text` under the name `name`) and read the
 * header. PST_EIO (cannot open, read error), PST_EINPUT (no header: "PATH:1:1: empty file: no
 * header line", a bad record), PST_ENOMEM; *out is NULL on failure. */
int pst_csv_open(pst_csv_reader **out, const char *path, int flags, char *err);
int pst_csv_open_text(pst_csv_reader **out, const char *text, const char *name, int flags,
                      char *err);
/* Close the file and free the reader (NULL allowed). */
void pst_csv_close(pst_csv_reader *r);

/* The next data record: PST_OK with *got 1, or *got 0 at the end of the file. PST_EINPUT for a
 * record whose cell count is not the header's ("expected N columns, found M" at the first
 * missing or extra cell), an unterminated quoted cell, text after a closing quote, a NUL byte,
 * a record over a cap; PST_EIO on a read error; PST_ENOMEM. */
int pst_csv_next(pst_csv_reader *r, int *got, char *err);

/* The header: its cell count and cell k. */
size_t pst_csv_ncols(const pst_csv_reader *r);
const char *pst_csv_name(const pst_csv_reader *r, size_t k);
/* Cell k (< pst_csv_ncols) of the current record (after pst_csv_open: of the header), valid
 * until the next call; the record's first line; the path messages use. */
const char *pst_csv_cell(const pst_csv_reader *r, size_t k);
size_t pst_csv_line(const pst_csv_reader *r);
const char *pst_csv_path(const pst_csv_reader *r);

/* What a cell is as a number: the whole cell must be one strtod() number (leading spaces
 * allowed), finite. */
typedef enum {
    PST_CSV_NUMBER,
    PST_CSV_EMPTY,
    PST_CSV_NOT_A_NUMBER,
    PST_CSV_NOT_FINITE
} pst_csv_num;
/* *v (untouched unless PST_CSV_NUMBER) and what the cell is. */
pst_csv_num pst_csv_parse_number(const char *cell, double *v);

/* Cell k of the current record as a finite number, or PST_EINPUT with "PATH:LINE:COLUMN:
 * column NAME: missing value" (or "cannot parse 'CELL' as a number", "value 'CELL' is not
 * finite"). */
int pst_csv_number(const pst_csv_reader *r, size_t k, double *v, char *err);

/* Write "PATH:LINE:COLUMN: column NAME: MESSAGE" for cell k of the current record into err and
 * return `code`: the message of any check a format makes on a cell. */
int pst_csv_cell_error(const pst_csv_reader *r, size_t k, int code, char *err,
                       const char *fmt, ...) __attribute__((format(printf, 5, 6)));

/* A small CSV file whole, as strings and as numbers, for tables such as sweep results. */
typedef struct {
    size_t nrows; /* data rows, without the header                                          */
    int ncols;
    char **cell;  /* (nrows + 1) * ncols strings: cell[r * ncols + c], row 0 the header      */
    double *num;  /* the same layout: each data cell as a finite number, NAN when it is not
                     one (empty, text, nan, inf: pst_csv_parse_number); row 0 all NAN       */
    size_t cap;   /* rows allocated                                                          */
} pst_csv_table;

/* Read a whole file (pst_csv_read_table) or text (pst_csv_parse_table) into a table with the
 * reader's flags and errors, and PST_EINPUT beyond PST_CSV_MAX_ROWS data rows. *t is empty on
 * failure. */
int pst_csv_read_table(pst_csv_table *t, const char *path, int flags, char *err);
int pst_csv_parse_table(pst_csv_table *t, const char *text, const char *name, int flags,
                        char *err);
/* Append a row of ncols cells (copied, numbers parsed once); to a zeroed table the first
 * row appended is the header and sets ncols (> 0). PST_EINVAL for ncols <= 0 or above
 * PST_CSV_MAX_CELLS, PST_EINPUT beyond PST_CSV_MAX_ROWS, PST_ENOMEM. */
int pst_csv_table_add(pst_csv_table *t, int ncols, const char *const *cells, char *err);
/* Free the cells and zero the table (NULL allowed). */
void pst_csv_table_free(pst_csv_table *t);
/* The first column named `name` among the first `below` columns, or -1. */
int pst_csv_table_column(const pst_csv_table *t, const char *name, int below);

/* --- CSV clouds --------------------------------------------------------------------------- */

/* Read a cloud from CSV. The header names the columns: x,y[,z],V,h, then optionally kind
 * (default interior), optionally nx,ny[,nz] (default zero), optionally m (scalar mobility) or
 * mx,my[,mz] (diagonal), then any named fields, in that order. kind is "interior",
 * "dirichlet", "neumann" (or 0, 1, 2). Errors (PST_EINPUT / PST_EIO) name the file,
 * line and column in `err`: NaN/Inf, wrong column count, unknown kind, V or h <= 0, duplicate
 * particles. The cloud is Morton-unsorted: particle i is data line i. */
int pst_cloud_read_csv(pst_cloud **out, const char *path, char *err);

/* Write a cloud to CSV in input order (by ids), with full round-trip precision (%.17g). The
 * file is written to a temporary name in the same directory and renamed, so a failed write
 * never leaves a half-written file. */
int pst_cloud_write_csv(const pst_cloud *c, const char *path, char *err);

/* --- VTU (ParaView) ------------------------------------------------------------------------ */

/* Write a cloud as a VTK XML UnstructuredGrid (.vtu) or, when `path` ends in .vtp (any case),
 * PolyData (Points and one vertex per point in Verts, for vtkXMLPolyDataReader); binary
 * appended data, little-endian, UInt64 headers: the particles as Points (z = 0 in 2D), one
 * VTK_VERTEX cell each, and the PointData arrays id, kind, V, h, normal (3 components), m or M
 * (when the cloud has a mobility; M is the diagonal, 3 components), status (when `row_status`
 * is given), then the named fields (docs/io.md, "Vectors and tensors"): fields NAME_x, NAME_y
 * (and NAME_z: required in 3D, taken when present in 2D) as one Float64 array NAME of 3
 * components (z 0 in 2D); fields NAME_xx, NAME_yy, NAME_xy (2D) or NAME_xx, NAME_yy, NAME_zz,
 * NAME_xy, NAME_yz, NAME_xz (3D) as one array NAME of 6 components in ParaView's symmetric
 * tensor order XX, YY, ZZ, XY, YZ, XZ (0 for those 2D lacks); NAME "normal" or "M" never
 * groups; every other field 1 component. Each array sits where its first field is. Particles
 * are written in input order (by ids), so a file does not depend on the cloud's storage order
 * or the thread count. `row_status` (may be NULL) holds n bytes in cloud order, e.g.
 * pst_op_status(). `flags` PST_VTK_ZLIB compresses every array with zlib in the layout of
 * VTK's vtkZLibDataCompressor (blocks of 32 KiB; compressor="vtkZLibDataCompressor"). All or
 * nothing, like the CSV writer: PST_EIO on a failed write, PST_EINVAL when the ids are not a
 * permutation or two PointData arrays would have one name (a field named like one of the
 * arrays above, e.g. "normal" or "status", or a scalar field u beside fields u_x, u_y),
 * PST_ENOMEM; `err` names the path and the arrays. */
enum { PST_VTK_ZLIB = 1 };
int pst_cloud_write_vtk(const pst_cloud *c, const char *path, const uint8_t *row_status,
                        int flags, char *err);
/* pst_cloud_write_vtk with flags 0 (uncompressed). */
int pst_cloud_write_vtu(const pst_cloud *c, const char *path, const uint8_t *row_status,
                        char *err);

/* One dataset of a VTK Collection: its time value, its part number within that time (>= 0)
 * and its file name, relative to the directory of the .pvd file (written as given, XML
 * escaped). */
typedef struct {
    double timestep;
    int part;
    const char *file;
} pst_pvd_dataset;

/* Write a VTK Collection file (.pvd) listing n datasets in the order given, all or nothing
 * (pst_write_atomic). ParaView plays the timesteps as a time series and shows the parts of
 * one timestep together. PST_EINVAL (an empty file name, a non-finite timestep, a negative
 * part), PST_EIO; `err` names the path. */
int pst_write_pvd(const char *path, const pst_pvd_dataset *d, size_t n, char *err);

/* Read a cloud from a VTK XML UnstructuredGrid (.vtu) or PolyData (.vtp) file with one Piece
 * (docs/io.md, "Reading VTU"): DataArrays in format "appended" (encoding raw or base64),
 * "binary" (inline base64) or "ascii", UInt32 or UInt64 headers, either byte order,
 * uncompressed or zlib-compressed (compressor vtkZLibDataCompressor; other compressors are
 * refused), of any Int8..Int64, UInt8..UInt64, Float32 or Float64 type (converted to double).
 * Points give the positions: the cloud is 2D when every z is exactly 0, else 3D. PointData: V
 * and h (required), kind (0, 1, 2; default interior), normal (3 components), m (scalar
 * mobility) or M (3-component diagonal; x, y only in 2D), id (a permutation of 0..n-1: row k of
 * the file becomes particle id[k]; without it particle k is row k), status (ignored); every
 * other array NAME is a field with a valid field name: 1 component gives the field NAME, 3 (a
 * vector) NAME_x, NAME_y, NAME_z, 6 (ParaView's symmetric tensor XX, YY, ZZ, XY, YZ, XZ)
 * NAME_xx, NAME_yy, NAME_zz, NAME_xy, NAME_yz, NAME_xz; in 2D only the in-plane components
 * (NAME_x, NAME_y; NAME_xx, NAME_yy, NAME_xy) and the others must be 0. Cells are ignored.
 * Errors: PST_EIO (cannot open or read), PST_EINPUT (malformed or truncated file or compressed
 * data, non-finite value, V, h or mobility <= 0, unknown kind, bad ids, duplicate particles;
 * `err` names the file and "LINE:COLUMN" of the XML, or the array and the 0-based point, or the
 * offset into the appended data), PST_ENOMEM. On failure *out is NULL. */
int pst_cloud_read_vtu(pst_cloud **out, const char *path, char *err);

/* Read a cloud with the reader its file name's extension names (case-insensitive): .vtu and
 * .vtp by pst_cloud_read_vtu, .csv by pst_cloud_read_csv; nothing is guessed from the
 * contents. Any other name is PST_EINPUT ("PATH: unknown extension ..."); otherwise the
 * reader's own errors. The command line and the scenes' cloud.file read through it. */
int pst_cloud_read(pst_cloud **out, const char *path, char *err);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_IO_H */
