// A particle code's use of pstencil, in C++ without a cast: the cloud is filled from the code's
// own arrays, then a neighbour list, a QSFDI operator, its Laplacian of u = x^2 + y^2 (exactly 4
// on every interior row) and a Dirichlet solve of Lap u = 4 that recovers u. Exits 0 on success.
#include <pstencil.h>

#include <cmath>
#include <cstdio>
#include <vector>

int main()
{
    // The host's particles: a jittered 21 x 21 lattice of the unit square, edge particles fixed.
    const int side = 21;
    const double s0 = 1.0 / (side - 1);
    std::vector<double> px, py;
    std::vector<bool> edge;
    for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
            const bool e = i == 0 || j == 0 || i == side - 1 || j == side - 1;
            const double jx = e ? 0.0 : 0.2 * s0 * std::sin(7.0 * i + 3.0 * j);
            const double jy = e ? 0.0 : 0.2 * s0 * std::cos(5.0 * i - 2.0 * j);
            px.push_back(i * s0 + jx);
            py.push_back(j * s0 + jy);
            edge.push_back(e);
        }
    const size_t n = px.size();

    char err[PST_ERRLEN];
    pst_cloud *c = nullptr;
    if (pst_cloud_create(&c, 2, n, err) != PST_OK) {
        std::fprintf(stderr, "cloud: %s\n", err);
        return 1;
    }
    double *x = pst_cloud_coord(c, 0), *y = pst_cloud_coord(c, 1), *vol = pst_cloud_volume(c);
    uint8_t *kind = pst_cloud_kinds(c);
    for (size_t i = 0; i < n; ++i) {
        x[i] = px[i];
        y[i] = py[i];
        vol[i] = s0 * s0;
        kind[i] = edge[i] ? PST_DIRICHLET : PST_INTERIOR;
    }
    pst_op_opts oo;
    pst_op_defaults(&oo);
    oo.scheme = "qsfdi";
    oo.kernel = pst_scheme_default_kernel("qsfdi");
    const double support = pst_kernel_support(oo.kernel);
    pst_nlist *nl = nullptr;
    pst_op *op = nullptr;
    if (pst_cloud_set_h_uniform(c, 1.3 * s0, err) != PST_OK ||
        pst_cloud_validate(c, err) != PST_OK || pst_nlist_build(&nl, c, support, err) != PST_OK ||
        pst_op_create(&op, c, nl, &oo, err) != PST_OK) {
        std::fprintf(stderr, "set-up: %s\n", err);
        return 1;
    }

    std::vector<double> u(n), lu(n), b(n), v(n, 0.0);
    for (size_t i = 0; i < n; ++i)
        u[i] = x[i] * x[i] + y[i] * y[i];
    pst_op_apply(op, u.data(), lu.data());
    double lap_err = 0.0;
    for (size_t i = 0; i < n; ++i)
        if (kind[i] == PST_INTERIOR)
            lap_err = std::fmax(lap_err, std::fabs(lu[i] - 4.0));

    for (size_t i = 0; i < n; ++i)
        b[i] = kind[i] == PST_DIRICHLET ? u[i] : 4.0;
    pst_solve_opts so;
    pst_solve_defaults(&so);
    so.solver = PST_SOLVER_GMRES;
    so.rtol = 1e-12;
    pst_solve_result r;
    const int status = pst_solve(op, b.data(), v.data(), &so, &r, err);
    double sol_err = 0.0;
    for (size_t i = 0; i < n; ++i)
        sol_err = std::fmax(sol_err, std::fabs(v[i] - u[i]));
    const bool solved = status == PST_OK && r.stop == PST_STOP_CONVERGED;
    std::printf("pstencil %s (C++): %zu particles, kernel %s, max |Lap u - 4| = %.2e, "
                "solve: %s in %d iterations, max |u - exact| = %.2e\n",
                pst_version(), n, pst_kernel_name(pst_op_kernel(op)), lap_err,
                pst_stop_reason_name(r.stop), r.iterations, sol_err);
    pst_solve_result_free(&r);
    pst_op_destroy(op);
    pst_nlist_destroy(nl);
    pst_cloud_destroy(c);
    return lap_err < 1e-8 && solved && sol_err < 1e-8 ? 0 : 1;
}
