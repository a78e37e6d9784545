/* The status codes' names and the error-detail buffer (docs/errors.md). */
#include "internal.h"

#include <string.h>

void pst_escape_controls(char *msg, size_t cap)
{
    if (!msg || cap == 0)
        return;
    size_t len = strlen(msg), out = 0, keep = 0;
    /* how many input bytes fit, escaped, in cap - 1 bytes (an escape is never cut) */
    for (; keep < len; ++keep) {
        unsigned char ch = (unsigned char)msg[keep];
        size_t w = ch < 0x20 || ch == 0x7f ? 4 : 1;
        if (out + w > cap - 1)
            break;
        out += w;
    }
    msg[out] = '\0';
    while (keep > 0) { /* from the end, so that nothing is overwritten before it is read */
        unsigned char ch = (unsigned char)msg[--keep];
        if (ch < 0x20 || ch == 0x7f) {
            static const char hex[] = "0123456789abcdef";
            out -= 4;
            msg[out] = '\\';
            msg[out + 1] = 'x';
            msg[out + 2] = hex[ch >> 4];
            msg[out + 3] = hex[ch & 15];
        } else {
            msg[--out] = (char)ch;
        }
    }
}

void pst_set_err(char *err, const char *fmt, ...)
{
    if (!err)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, PST_ERRLEN, fmt, ap);
    va_end(ap);
    pst_escape_controls(err, PST_ERRLEN);
}

const char *pst_strerror(int status)
{
    switch (status) {
    case PST_OK: return "ok";
    case PST_EINVAL: return "invalid argument";
    case PST_EINPUT: return "bad input data";
    case PST_ENOMEM: return "out of memory";
    case PST_EIO: return "input/output error";
    case PST_ENUMERIC: return "numerical failure";
    default: return "unknown status";
    }
}
