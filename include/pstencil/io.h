/* pstencil: Reading and writing clouds: CSV and VTU. Part of the public API; include <pstencil.h>. */
#ifndef PSTENCIL_PUBLIC_IO_H
#define PSTENCIL_PUBLIC_IO_H

#include "pstencil/cloud.h"

#ifdef __cplusplus
extern "C" {
#endif

/* --- CSV ----------------------------------------------------------------------------------- */

/* Read a cloud from CSV. The header names the columns: x,y[,z],V,h,kind,nx,ny[,nz], then
 * optionally m (scalar mobility) or mx,my[,mz] (diagonal), then any named fields. kind is
 * "interior", "dirichlet", "neumann" (or 0, 1, 2). Errors (PST_EINPUT / PST_EIO) name the file,
 * line and column in `err`: NaN/Inf, wrong column count, unknown kind, V or h <= 0, duplicate
 * particles. The cloud is Morton-unsorted: particle i is data line i. */
int pst_cloud_read_csv(pst_cloud **out, const char *path, char *err);

/* Write a cloud to CSV in input order (by ids), with full round-trip precision (%.17g). The
 * file is written to a temporary name in the same directory and renamed, so a failed write
 * never leaves a half-written file. */
int pst_cloud_write_csv(const pst_cloud *c, const char *path, char *err);

/* --- VTU (ParaView) ------------------------------------------------------------------------ */

/* Write a cloud as a VTK XML UnstructuredGrid (.vtu), binary appended raw data, little-endian,
 * 64-bit byte-count headers: the particles as Points (z = 0 in 2D), one VTK_VERTEX cell each,
 * and the PointData arrays id, kind, V, h, normal (3 components), m or M (when the cloud has a
 * mobility; M is the diagonal, 3 components), status (when `row_status` is given) and every
 * named field (docs/io.md). Particles are written in input order (by ids), so a file does not
 * depend on the cloud's storage order or the thread count. `row_status` (may be NULL) holds n
 * bytes in cloud order, e.g. pst_op_status(). All or nothing, like the CSV writer: PST_EIO on a
 * failed write, PST_EINVAL when the ids are not a permutation or a field is named like one of
 * the arrays above ("normal", "M", "status"); `err` names the path. */
int pst_cloud_write_vtu(const pst_cloud *c, const char *path, const uint8_t *row_status,
                        char *err);

/* Read a cloud from a VTK XML UnstructuredGrid (.vtu) or PolyData (.vtp) file with one Piece
 * (docs/io.md, "Reading VTU"): DataArrays in format "appended" (encoding raw, UInt32 or UInt64
 * headers, either byte order), "binary" (inline base64, uncompressed) or "ascii", of any
 * Int8..Int64, UInt8..UInt64, Float32 or Float64 type (converted to double). Points give the
 * positions: the cloud is 2D when every z is exactly 0, else 3D. PointData: V and h (required),
 * kind (0, 1, 2; default interior), normal (3 components), m (scalar mobility) or M (3-component
 * diagonal; x, y only in 2D), id (a permutation of 0..n-1: row k of the file becomes particle
 * id[k]; without it particle k is row k), status (ignored); every other array is a named field
 * and must have 1 component and a valid field name. Cells are ignored. Compressed files are
 * refused. Errors: PST_EIO (cannot open or read), PST_EINPUT (malformed or truncated file,
 * non-finite value, V, h or mobility <= 0, unknown kind, bad ids, duplicate particles; `err`
 * names the file and "LINE:COLUMN" of the XML, or the array and the 0-based point, or the offset
 * into the appended data), PST_ENOMEM. On failure *out is NULL. */
int pst_cloud_read_vtu(pst_cloud **out, const char *path, char *err);

#ifdef __cplusplus
}
#endif

#endif /* PSTENCIL_PUBLIC_IO_H */
