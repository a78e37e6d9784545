/* The values of a DataArray: appended raw or base64 bytes, inline base64 ("binary") or
 * ascii, each size checked against the bytes that are there, converted to double; compressed
 * arrays go to io_vtu_zlib.c. Base64 is decoded here because neither expat nor zlib does it. */
#include "vtu_read.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

const vtk_type vtk_types[NTYPES] = {{"Int8", 1, 0, 1},  {"UInt8", 1, 0, 0},  {"Int16", 2, 0, 1},
                 {"UInt16", 2, 0, 0}, {"Int32", 4, 0, 1}, {"UInt32", 4, 0, 0},
                 {"Int64", 8, 0, 1},  {"UInt64", 8, 0, 0}, {"Float32", 4, 1, 1},
                 {"Float64", 8, 1, 1}};

uint64_t vtu_load_uint(const unsigned char *p, int size, int big)
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
    uint64_t u = vtu_load_uint(p, size, big);
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
 * quantum, so separately encoded blocks that follow one another decode too. */
long long vtu_b64_decode(char *s, size_t len, size_t *bad)
{
    size_t o = 0;
    int q[4] = {0, 0, 0, 0}, nq = 0, pad = 0;
    for (size_t i = 0; i <= len; ++i) {
        int ch = i < len ? (unsigned char)s[i] : -1;
        if (ch >= 0 && vtu_is_space(ch))
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

size_t vtu_b64_take(vtu_b64_stream *b, unsigned char *out, size_t want)
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
            if (vtu_is_space(ch)) {
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

uint64_t vtu_expect_bytes(const reader *r, const vtu_in_array *a)
{
    return r->npoints * (uint64_t)a->ncomp * (uint64_t)vtk_types[a->type].size;
}

void vtu_convert(const reader *r, const vtu_in_array *a, const unsigned char *p, double *out,
                    size_t count)
{
    int size = vtk_types[a->type].size;
    for (size_t k = 0; k < count; ++k)
        out[k] = load_value(p + k * (size_t)size, a->type, r->big_endian);
}

/* An appended block whose header gives `bytes` where the array needs `want`. */
static int appended_count_error(reader *r, const vtu_in_array *a, uint64_t bytes, uint64_t want)
{
    return vtu_fail(r,
                    "appended data offset %llu (array '%.64s'): byte count %llu, expected "
                    "%llu (%llu points x %d components x %d bytes)",
                    (unsigned long long)a->offset, a->name, (unsigned long long)bytes,
                    (unsigned long long)want, (unsigned long long)r->npoints, a->ncomp,
                    vtk_types[a->type].size);
}

/* An appended array in a base64 block: header and data decoded from its offset on. */
static int decode_appended_b64(reader *r, const vtu_in_array *a, const unsigned char *p,
                               size_t avail, double *out)
{
    int hs = r->header_size;
    uint64_t want = vtu_expect_bytes(r, a);
    vtu_b64_stream b = {.s = p, .len = avail};
    unsigned char hdr[8];
    if (vtu_b64_take(&b, hdr, (size_t)hs) != (size_t)hs)
        return vtu_fail(r,
                        "appended data offset %llu (array '%.64s'): truncated or invalid "
                        "base64 header",
                        (unsigned long long)a->offset, a->name);
    uint64_t bytes = vtu_load_uint(hdr, hs, r->big_endian);
    if (bytes != want)
        return appended_count_error(r, a, bytes, want);
    if (bytes / 3 > (b.len - b.pos) / 4 + 1)
        return vtu_fail(r,
                        "appended data offset %llu (array '%.64s'): truncated: %llu bytes "
                        "of data do not fit in the rest of the block",
                        (unsigned long long)a->offset, a->name, (unsigned long long)bytes);
    unsigned char *raw = malloc(bytes ? (size_t)bytes : 1);
    if (!raw)
        return vtu_oom(r);
    size_t got = vtu_b64_take(&b, raw, (size_t)bytes);
    if (got != bytes) {
        free(raw);
        return vtu_fail(r,
                        "appended data offset %llu (array '%.64s'): truncated or invalid "
                        "base64 data: %zu of %llu bytes",
                        (unsigned long long)a->offset, a->name, got, (unsigned long long)bytes);
    }
    vtu_convert(r, a, raw, out, (size_t)r->npoints * (size_t)a->ncomp);
    free(raw);
    return PST_OK;
}

/* An appended array: raw bytes, or base64 when the block is. */
static int decode_appended(reader *r, const vtu_in_array *a, double *out)
{
    int hs = r->header_size;
    if (!r->have_appended)
        return vtu_fail_at(r, a->at,
                           "array '%.64s' is format=\"appended\" but the file has no "
                           "<AppendedData>",
                           a->name);
    size_t avail = r->data_end - r->data;
    if (a->offset > avail || avail - a->offset < (uint64_t)hs)
        return vtu_fail(r,
                        "appended data offset %llu (array '%.64s'): beyond the end of the "
                        "appended block (%zu bytes)",
                        (unsigned long long)a->offset, a->name, avail);
    const unsigned char *p = r->buf + r->data + a->offset;
    if (r->compressed) {
        vtu_b64_stream b = {.s = p, .len = avail - a->offset};
        vtu_source src = {.p = p, .len = avail - a->offset, .b64 = r->appended_b64 ? &b : NULL};
        return vtu_decode_zlib(r, a, &src, out);
    }
    if (r->appended_b64)
        return decode_appended_b64(r, a, p, avail - a->offset, out);
    uint64_t want = vtu_expect_bytes(r, a), bytes = vtu_load_uint(p, hs, r->big_endian);
    if (bytes != want)
        return appended_count_error(r, a, bytes, want);
    if (bytes > avail - a->offset - (uint64_t)hs)
        return vtu_fail(r,
                        "appended data offset %llu (array '%.64s'): truncated: %llu bytes of "
                        "data, only %llu left in the appended block",
                        (unsigned long long)a->offset, a->name, (unsigned long long)bytes,
                        (unsigned long long)(avail - a->offset - (uint64_t)hs));
    vtu_convert(r, a, p + hs, out, (size_t)r->npoints * (size_t)a->ncomp);
    return PST_OK;
}

/* An inline base64 ("binary") array, decoded in place. */
static int decode_binary(reader *r, vtu_in_array *a, double *out)
{
    int hs = r->header_size;
    uint64_t want = vtu_expect_bytes(r, a);
    size_t bad = 0;
    long long got = vtu_b64_decode(a->text, a->text_len, &bad);
    if (got < 0)
        return vtu_fail_at(r, a->at,
                           "array '%.64s': invalid base64 at character %zu of its "
                           "data",
                           a->name, bad + 1);
    const unsigned char *p = (const unsigned char *)a->text;
    if (r->compressed) {
        vtu_source src = {.p = p, .len = (size_t)got};
        return vtu_decode_zlib(r, a, &src, out);
    }
    if ((uint64_t)got < (uint64_t)hs)
        return vtu_fail_at(r, a->at,
                           "array '%.64s': truncated binary data: %lld bytes, no "
                           "room for the %d-byte header",
                           a->name, got, hs);
    uint64_t bytes = vtu_load_uint(p, hs, r->big_endian);
    if (bytes != want)
        return vtu_fail_at(r, a->at,
                           "array '%.64s': binary byte count %llu, expected %llu "
                           "(%llu points x %d components x %d bytes)",
                           a->name, (unsigned long long)bytes, (unsigned long long)want,
                           (unsigned long long)r->npoints, a->ncomp, vtk_types[a->type].size);
    if ((uint64_t)got - (uint64_t)hs != bytes)
        return vtu_fail_at(r, a->at,
                           "array '%.64s': binary data holds %llu bytes after the "
                           "header, the header says %llu",
                           a->name, (unsigned long long)((uint64_t)got - (uint64_t)hs),
                           (unsigned long long)bytes);
    vtu_convert(r, a, p + hs, out, (size_t)r->npoints * (size_t)a->ncomp);
    return PST_OK;
}

/* An ascii array: white-space separated numbers, exactly npoints * ncomp of them. */
static int decode_ascii(reader *r, const vtu_in_array *a, double *out)
{
    size_t count = (size_t)r->npoints * (size_t)a->ncomp, k = 0;
    char *s = a->text;
    for (;;) {
        while (vtu_is_space((unsigned char)*s))
            ++s;
        if (!*s)
            break;
        char *end;
        errno = 0;
        double v = strtod(s, &end); /* ERANGE on subnormals is fine */
        if (end == s || (*end && !vtu_is_space((unsigned char)*end))) {
            size_t tl = 0;
            while (s[tl] && !vtu_is_space((unsigned char)s[tl]))
                ++tl;
            return vtu_fail_at(r, a->at,
                               "array '%.64s': value %zu: cannot parse '%.*s' as a "
                               "number",
                               a->name, k + 1, (int)(tl < 40 ? tl : 40), s);
        }
        if (k < count)
            out[k] = v;
        ++k;
        s = end;
    }
    if (k != count)
        return vtu_fail_at(r, a->at,
                           "array '%.64s' holds %zu values, expected %zu (%llu points "
                           "x %d components)",
                           a->name, k, count, (unsigned long long)r->npoints, a->ncomp);
    return PST_OK;
}

int vtu_decode(reader *r, vtu_in_array *a, double *out)
{
    if (a->format == FMT_APPENDED)
        return decode_appended(r, a, out);
    if (a->format == FMT_BINARY)
        return decode_binary(r, a, out);
    return decode_ascii(r, a, out);
}
