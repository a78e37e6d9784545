/* A tiny test harness: CHECK-style assertions that count failures and report where they
 * happened; a test program returns check_summary() as its exit status. */
#ifndef PSTENCIL_TEST_CHECK_H
#define PSTENCIL_TEST_CHECK_H

#include <math.h>
#include <stdio.h>

static int check_failures;
static int check_count;

#define CHECK(cond)                                                                            \
    do {                                                                                       \
        ++check_count;                                                                         \
        if (!(cond)) {                                                                         \
            ++check_failures;                                                                  \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);          \
        }                                                                                      \
    } while (0)

/* |a - b| <= tol, with both values printed on failure. */
#define CHECK_NEAR(a, b, tol)                                                                  \
    do {                                                                                       \
        double check_a_ = (a), check_b_ = (b), check_t_ = (tol);                               \
        ++check_count;                                                                         \
        if (!(fabs(check_a_ - check_b_) <= check_t_)) {                                        \
            ++check_failures;                                                                  \
            fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.17g, %s = %.17g, tol %.3g\n",    \
                    __FILE__, __LINE__, #a, check_a_, #b, check_b_, check_t_);                 \
        }                                                                                      \
    } while (0)

#define CHECK_INT(a, b)                                                                        \
    do {                                                                                       \
        long long check_a_ = (long long)(a), check_b_ = (long long)(b);                        \
        ++check_count;                                                                         \
        if (check_a_ != check_b_) {                                                            \
            ++check_failures;                                                                  \
            fprintf(stderr, "%s:%d: CHECK_INT failed: %s = %lld, %s = %lld\n", __FILE__,       \
                    __LINE__, #a, check_a_, #b, check_b_);                                     \
        }                                                                                      \
    } while (0)

static inline int check_summary(const char *name)
{
    printf("%s: %d checks, %d failed\n", name, check_count, check_failures);
    return check_failures ? 1 : 0;
}

#endif
