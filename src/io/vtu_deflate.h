/* The zlib-compressed form of one appended array (vtkZLibDataCompressor). Private to io/. */
#ifndef PSTENCIL_VTU_DEFLATE_H
#define PSTENCIL_VTU_DEFLATE_H

#include <stddef.h>

/* Compress `len` bytes of `raw` in blocks of PST_VTU_ZLIB_BLOCK bytes into a fresh buffer
 * *out of *outlen bytes: the UInt64 little-endian header (number of blocks, block size, size
 * of the last partial block or 0, each block's compressed size), then the blocks. PST_OK or
 * PST_ENOMEM (*out NULL). */
enum { PST_VTU_ZLIB_BLOCK = 1 << 15 };
int pst_vtu_zlib_pack(const unsigned char *raw, size_t len, unsigned char **out, size_t *outlen);

#endif
