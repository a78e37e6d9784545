/* zlib compression of a VTU array in the layout of VTK's vtkZLibDataCompressor (docs/io.md):
 * blocks compressed one by one, so that a reader can inflate them independently. */
#include "vtu_deflate.h"

#include "pstencil/core.h"

#include <stdint.h>
#include <stdlib.h>
#include <zlib.h>

static void put_le64(unsigned char *p, uint64_t v)
{
    for (int b = 0; b < 8; ++b)
        p[b] = (unsigned char)(v >> (8 * b));
}

int pst_vtu_zlib_pack(const unsigned char *raw, size_t len, unsigned char **out, size_t *outlen)
{
    const size_t bs = PST_VTU_ZLIB_BLOCK;
    size_t nb = len / bs + (len % bs != 0), head = 8 * (3 + nb);
    size_t cap = head + nb * (size_t)compressBound((uLong)bs);
    unsigned char *buf = malloc(cap);
    *out = NULL;
    if (!buf)
        return PST_ENOMEM;
    put_le64(buf, nb);
    put_le64(buf + 8, bs);
    put_le64(buf + 16, len % bs);
    size_t at = head;
    for (size_t b = 0; b < nb; ++b) {
        size_t in = b + 1 < nb || len % bs == 0 ? bs : len % bs;
        uLongf got = (uLongf)(cap - at);
        /* compress2 fails only for a short buffer or no memory; the buffer has the bound */
        if (compress2(buf + at, &got, raw + b * bs, (uLong)in, Z_DEFAULT_COMPRESSION) != Z_OK) {
            free(buf);
            return PST_ENOMEM;
        }
        put_le64(buf + 8 * (3 + b), got);
        at += got;
    }
    *out = buf;
    *outlen = at;
    return PST_OK;
}
