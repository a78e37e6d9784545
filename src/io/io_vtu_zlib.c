/* zlib-compressed DataArrays (compressor="vtkZLibDataCompressor"). VTK's layout: a header of
 * header_type words [number of blocks, uncompressed block size, uncompressed size of the last
 * block (0: a full block), compressed size of each block], then the blocks, each one zlib
 * stream. Inline ("binary") and appended base64 encode the header and the blocks as two runs;
 * the base64 decoders read across the padding in between. Every size from the file is checked
 * against the array's expected byte count and the bytes that are there before it is used. */
#include "vtu_read.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* Take up to `want` bytes of the source; how many were there. A block of 0 compressed bytes
 * (a file's word) takes none, with no buffer allocated yet (out NULL). */
static size_t src_take(vtu_source *s, unsigned char *out, size_t want)
{
    if (want == 0)
        return 0;
    if (s->b64)
        return vtu_b64_take(s->b64, out, want);
    size_t n = s->len - s->pos < want ? s->len - s->pos : want;
    memcpy(out, s->p + s->pos, n);
    s->pos += n;
    return n;
}

/* At most how many bytes the source still holds (base64: 3 per 4 characters left). */
static size_t src_left(const vtu_source *s)
{
    if (s->b64)
        return (s->b64->len - s->b64->pos) / 4 * 3 + 3 + (size_t)s->b64->npend;
    return s->len - s->pos;
}

/* The error of a compressed array, placed as its uncompressed form's errors are: the offset
 * of an appended array, the LINE:COLUMN of an inline one. */
__attribute__((format(printf, 3, 4))) static int zfail(reader *r, const vtu_in_array *a,
                                                       const char *fmt, ...)
{
    char msg[PST_ERRLEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (a->format == FMT_APPENDED)
        return vtu_fail(r, "appended data offset %llu (array '%.64s'): compressed data: %s",
                        (unsigned long long)a->offset, a->name, msg);
    return vtu_fail_at(r, a->at, "array '%.64s': compressed data: %s", a->name, msg);
}

/* The block layout of the header: nb blocks of bs bytes, the last of last_size; checked
 * against the array's byte count `want` and the source's size. */
static int read_layout(reader *r, const vtu_in_array *a, vtu_source *src, uint64_t *nb,
                       uint64_t *bs, uint64_t *last_size)
{
    int hs = r->header_size;
    unsigned char h[24];
    if (src_take(src, h, 3 * (size_t)hs) != 3 * (size_t)hs)
        return zfail(r, a, "truncated header (%d bytes)", 3 * hs);
    *nb = vtu_load_uint(h, hs, r->big_endian);
    *bs = vtu_load_uint(h + hs, hs, r->big_endian);
    uint64_t last = vtu_load_uint(h + 2 * hs, hs, r->big_endian);
    uint64_t want = vtu_expect_bytes(r, a);
    if (*nb > src_left(src) / (size_t)hs)
        return zfail(r, a, "the header declares %llu blocks, more than the %zu bytes left can "
                     "describe", (unsigned long long)*nb, src_left(src));
    *last_size = last ? last : *bs;
    uint64_t total = 0;
    if (*nb > 0 && (*bs == 0 || *last_size > *bs || *nb - 1 > want / *bs))
        total = UINT64_MAX; /* more than any array here */
    else if (*nb > 0)
        total = (*nb - 1) * *bs + *last_size;
    if (total != want)
        return zfail(r, a,
                     "uncompressed size %s%llu (%llu blocks of %llu bytes, the last %llu), "
                     "expected %llu (%llu points x %d components x %d bytes)",
                     total == UINT64_MAX ? "over " : "",
                     (unsigned long long)(total == UINT64_MAX ? want : total),
                     (unsigned long long)*nb, (unsigned long long)*bs,
                     (unsigned long long)*last_size, (unsigned long long)want,
                     (unsigned long long)r->npoints, a->ncomp, vtk_types[a->type].size);
    return PST_OK;
}

/* Inflate block b (csize bytes of the source) into out, which holds exactly usize bytes. */
static int inflate_block(reader *r, const vtu_in_array *a, vtu_source *src, uint64_t b,
                         uint64_t nb, uint64_t csize, unsigned char *out, uint64_t usize,
                         unsigned char **cbuf, size_t *ccap)
{
    size_t left = src_left(src);
    if (csize > left)
        return zfail(r, a, "block %llu of %llu: truncated: %llu compressed bytes, at most %zu "
                     "left", (unsigned long long)b + 1, (unsigned long long)nb,
                     (unsigned long long)csize, left);
    if (csize > *ccap) {
        unsigned char *nc = realloc(*cbuf, (size_t)csize);
        if (!nc)
            return vtu_oom(r);
        *cbuf = nc;
        *ccap = (size_t)csize;
    }
    size_t got = src_take(src, *cbuf, (size_t)csize);
    if (got != csize)
        return zfail(r, a, "block %llu of %llu: truncated: %zu of %llu compressed bytes",
                     (unsigned long long)b + 1, (unsigned long long)nb, got,
                     (unsigned long long)csize);
    uLongf dlen = (uLongf)usize;
    int zst = uncompress(out, &dlen, *cbuf, (uLong)csize);
    if (zst == Z_BUF_ERROR)
        return zfail(r, a, "block %llu of %llu inflates to more than its %llu bytes",
                     (unsigned long long)b + 1, (unsigned long long)nb,
                     (unsigned long long)usize);
    if (zst != Z_OK)
        return zfail(r, a, "block %llu of %llu: corrupt zlib stream (%s)",
                     (unsigned long long)b + 1, (unsigned long long)nb, zError(zst));
    if (dlen != usize)
        return zfail(r, a, "block %llu of %llu inflates to %llu bytes, the header says %llu",
                     (unsigned long long)b + 1, (unsigned long long)nb,
                     (unsigned long long)dlen, (unsigned long long)usize);
    return PST_OK;
}

int vtu_decode_zlib(reader *r, const vtu_in_array *a, vtu_source *src, double *out)
{
    int hs = r->header_size;
    uint64_t nb = 0, bs = 0, last_size = 0;
    int st = read_layout(r, a, src, &nb, &bs, &last_size);
    if (st != PST_OK)
        return st;
    uint64_t want = vtu_expect_bytes(r, a);
    unsigned char *sizes = malloc(nb ? (size_t)nb * (size_t)hs : 1),
                  *raw = malloc(want ? (size_t)want : 1), *cbuf = NULL;
    size_t ccap = 0;
    if (!sizes || !raw)
        st = vtu_oom(r);
    else if (src_take(src, sizes, (size_t)nb * (size_t)hs) != (size_t)nb * (size_t)hs)
        st = zfail(r, a, "truncated header: the sizes of %llu blocks", (unsigned long long)nb);
    for (uint64_t b = 0; st == PST_OK && b < nb; ++b)
        st = inflate_block(r, a, src, b, nb,
                           vtu_load_uint(sizes + b * (uint64_t)hs, hs, r->big_endian),
                           raw + b * bs, b + 1 == nb ? last_size : bs, &cbuf, &ccap);
    if (st == PST_OK)
        vtu_convert(r, a, raw, out, (size_t)r->npoints * (size_t)a->ncomp);
    free(cbuf);
    free(raw);
    free(sizes);
    return st;
}
