/* The inline small dense algebra (src/small_matrix.h): closed-form 2x2/3x3 inverses with their
 * condition numbers, LDL^T on SPD Gram matrices and LU with pivoting on general matrices up to
 * 10x10, against known solutions; singular inputs are reported, never divided by. */
#include "check.h"
#include "small_matrix.h"

#include <stdlib.h>

static double rnd(void) { return rand() / (double)RAND_MAX - 0.5; }

int main(void)
{
    srand(3);
    for (int n = 2; n <= 10; ++n) {
        double M[100], A[100], F[100], x[10], b[10], c[10];
        int piv[10];
        for (int i = 0; i < n * n; ++i)
            M[i] = rnd();
        for (int i = 0; i < n; ++i) /* A = M M^T + I: SPD */
            for (int j = 0; j < n; ++j) {
                double s = i == j;
                for (int k = 0; k < n; ++k)
                    s += M[i * n + k] * M[j * n + k];
                A[i * n + j] = s;
            }
        for (int i = 0; i < n; ++i)
            x[i] = i + 1;
        for (int i = 0; i < n; ++i) {
            b[i] = c[i] = 0;
            for (int j = 0; j < n; ++j) {
                b[i] += A[i * n + j] * x[j];
                c[i] += M[i * n + j] * x[j];
            }
        }
        for (int i = 0; i < n * n; ++i)
            F[i] = A[i];
        CHECK(pst_ldlt_factor(n, F) > 1e-3);
        pst_ldlt_solve(n, F, b);
        for (int i = 0; i < n * n; ++i)
            F[i] = M[i];
        CHECK(pst_lu_factor(n, F, piv) > 0);
        pst_lu_solve(n, F, piv, c);
        for (int i = 0; i < n; ++i) {
            CHECK_NEAR(b[i], x[i], 1e-12 * n);
            CHECK_NEAR(c[i], x[i], 1e-9 * n);
        }
        /* a rank-deficient Gram matrix (two equal rows/columns) is not SPD */
        for (int i = 0; i < n * n; ++i)
            F[i] = A[i];
        for (int j = 0; j < n; ++j) {
            F[1 * n + j] = F[0 * n + j];
            F[j * n + 1] = F[j * n + 0];
        }
        CHECK(pst_ldlt_factor(n, F) <= 1e-12);
        for (int i = 0; i < n * n; ++i)
            F[i] = M[i];
        for (int j = 0; j < n; ++j)
            F[1 * n + j] = 2 * F[0 * n + j];
        CHECK(pst_lu_factor(n, F, piv) <= 1e-12);
    }
    /* closed form: inverse, condition number and singular matrices */
    double a2[4] = {4, 1, 2, 3}, i2[4];
    CHECK_NEAR(pst_mat_inverse(2, a2, i2), 3.0, 1e-14); /* ||a||1 = 6, ||a^-1||1 = 0.5 */
    CHECK_NEAR(i2[0], 0.3, 1e-15);
    CHECK_NEAR(i2[1], -0.1, 1e-15);
    double a3[9] = {2, 0, 0, 0, 4, 0, 0, 0, 8}, i3[9];
    CHECK_NEAR(pst_mat_inverse(3, a3, i3), 4.0, 1e-15);
    CHECK_NEAR(i3[8], 0.125, 1e-16);
    double s3[9] = {1, 2, 3, 2, 4, 6, 0, 1, 1};
    CHECK(pst_mat_inverse(3, s3, i3) == INFINITY);
    double sdd[4] = {3, -1, 1, 2}, notsdd[4] = {1, 2, 0, 3}, neg[4] = {-3, 1, 0, 2};
    CHECK(pst_mat_sdd_positive(2, sdd));
    CHECK(!pst_mat_sdd_positive(2, notsdd));
    CHECK(!pst_mat_sdd_positive(2, neg));
    return check_summary("test_small_matrix");
}
