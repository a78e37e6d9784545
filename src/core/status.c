/* The status codes' names and the error-detail buffer (docs/errors.md). */
#include "internal.h"

void pst_set_err(char *err, const char *fmt, ...)
{
    if (!err)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, PST_ERRLEN, fmt, ap);
    va_end(ap);
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
