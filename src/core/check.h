/* The library's one error convention: a call returns PST_OK or a PST_E* code and, where it can
 * fail for more than one reason, writes the reason into the caller's `char *err` (PST_ERRLEN
 * bytes, NULL allowed). These macros keep a check to one line (docs/errors.md). Private to the
 * library. */
#ifndef PSTENCIL_CHECK_H
#define PSTENCIL_CHECK_H

#include "internal.h"

/* Return the status of `call` when it is not PST_OK (the callee has written err). */
#define PST_TRY(call)                                                                        \
    do {                                                                                     \
        int pst_try_status_ = (call);                                                        \
        if (pst_try_status_ != PST_OK)                                                       \
            return pst_try_status_;                                                          \
    } while (0)

/* When `cond` holds: write the printf-style message into err and return `code`. */
#define PST_CHECK(cond, code, err, ...)                                                      \
    do {                                                                                     \
        if (cond) {                                                                          \
            pst_set_err((err), __VA_ARGS__);                                                 \
            return (code);                                                                   \
        }                                                                                    \
    } while (0)

/* PST_CHECK for an allocation: PST_ENOMEM when `ptr` is NULL. */
#define PST_CHECK_ALLOC(ptr, err, ...) PST_CHECK(!(ptr), PST_ENOMEM, err, __VA_ARGS__)

/* The same two for a function that must release what it holds: set `status` and jump to the
 * function's one cleanup label instead of returning. */
#define PST_TRY_GOTO(status, call, label)                                                    \
    do {                                                                                     \
        if (((status) = (call)) != PST_OK)                                                   \
            goto label;                                                                      \
    } while (0)
#define PST_CHECK_GOTO(cond, status, code, label, err, ...)                                  \
    do {                                                                                     \
        if (cond) {                                                                          \
            pst_set_err((err), __VA_ARGS__);                                                 \
            (status) = (code);                                                               \
            goto label;                                                                      \
        }                                                                                    \
    } while (0)

#endif
