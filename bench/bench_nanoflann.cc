// pstencil's neighbour list against nanoflann's on the same cloud in the same run: the built-in
// scene's cloud (3D, 101^3, s0 = 0.01, jitter 0.5, h = 1.2 s0, radius 3h = 3.6 s0) and its 2D
// counterpart (1001^2, s0 = 0.001), Morton-sorted as `pstencil run` sorts it. The peer is what
// a user of nanoflann writes: its KD-tree, then one radiusSearch per particle, threaded with
// OpenMP over the query points, each thread appending its rows to its own buffer, then a scan of
// the row lengths and a copy into one CSR list with rows sorted by index (pstencil's contract).
// Both sides are timed from the cloud to the finished CSR; they alternate, and so do the thread
// counts (1 and 2) within each repetition; the medians and their ratio are printed. The two
// lists are checked entry for entry once per cloud: the same rule (squared distance summed x,
// y, z, strict <) on the same doubles gives the same list. Last, pstencil's 1 -> 2 thread
// ratio once more from its builds alone, alternated.
//
//   bench_nanoflann [repetitions (default 5)] [dims: 3, 2 or 23 (default 23)]
#include <nanoflann.hpp>

#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

extern "C" {
#include "bench_common.h"
}

namespace {

constexpr double kSupport = 3.0; // quintic spline: R = 3h

// nanoflann's dataset adaptor over the cloud's SoA coordinates.
struct cloud_points {
    const double *x[3];
    size_t n;
    size_t kdtree_get_point_count() const { return n; }
    double kdtree_get_pt(size_t i, size_t d) const { return x[d][i]; }
    template <class Box> bool kdtree_get_bbox(Box &) const { return false; }
};

template <int D>
using kdtree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, cloud_points>, cloud_points, D, uint32_t>;

struct csr {
    std::vector<int64_t> offset;
    std::vector<uint32_t> index;
};

// nanoflann's CSR list: neighbours j != i with |x_j - x_i|^2 < r2, rows sorted by index.
template <int D> void nanoflann_list(const cloud_points &pts, double r2, csr &out)
{
    kdtree<D> tree(D, pts, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    size_t n = pts.n;
    out.offset.assign(n + 1, 0);
    int nt = omp_get_max_threads();
    std::vector<std::vector<uint32_t>> part(nt);
#pragma omp parallel num_threads(nt)
    {
        int t = omp_get_thread_num();
        std::vector<std::pair<uint32_t, double>> hits;
        std::vector<uint32_t> &mine = part[t];
        mine.reserve(n / nt * 200);
        nanoflann::SearchParams params(32, 0, false); // unsorted: sorted by index below
        size_t lo = n * t / nt, hi = n * (t + 1) / nt;
        for (size_t i = lo; i < hi; ++i) {
            double q[D];
            for (int d = 0; d < D; ++d)
                q[d] = pts.x[d][i];
            tree.radiusSearch(q, r2, hits, params);
            size_t before = mine.size();
            for (const auto &h : hits)
                if (h.first != i)
                    mine.push_back(h.first);
            std::sort(mine.begin() + before, mine.end());
            out.offset[i + 1] = (int64_t)(mine.size() - before);
        }
#pragma omp barrier
#pragma omp single
        {
            for (size_t i = 0; i < n; ++i)
                out.offset[i + 1] += out.offset[i];
            out.index.resize((size_t)out.offset[n]);
        }
        std::memcpy(out.index.data() + out.offset[lo], mine.data(), mine.size() * sizeof(uint32_t));
    }
}

int same_list(const pst_nlist *nl, const csr &peer, size_t n)
{
    const int64_t *off = pst_nlist_offsets(nl);
    const uint32_t *idx = pst_nlist_indices(nl);
    if (std::memcmp(off, peer.offset.data(), (n + 1) * sizeof *off) != 0)
        return 0;
    return std::memcmp(idx, peer.index.data(), (size_t)off[n] * sizeof *idx) == 0;
}

// The scene's cloud (dim 3) or its 2D counterpart, Morton-sorted on cells of the radius.
pst_cloud *scene_cloud(int dim)
{
    pst_lattice_opts o = bench_box(dim, 1, dim == 3 ? 0.01 : 0.001, 0.5, 1.2);
    o.seed = 1;
    o.boundary_layer = 1;
    pst_cloud *c = bench_lattice("bench_nanoflann", &o);
    if (c && pst_cloud_morton_sort(c, kSupport * pst_cloud_h_max(c), NULL) != PST_OK) {
        pst_cloud_destroy(c);
        return NULL;
    }
    return c;
}

// pstencil's list of c (radius kSupport h) built on `threads` threads, its wall time in
// *seconds; NULL after a message.
pst_nlist *pstencil_list(const pst_cloud *c, int threads, double *seconds)
{
    char err[PST_ERRLEN];
    pst_nlist *nl = NULL;
    omp_set_num_threads(threads);
    double t0 = omp_get_wtime();
    int st = pst_nlist_build(&nl, c, kSupport, err);
    *seconds = omp_get_wtime() - t0;
    if (st != PST_OK) {
        std::fprintf(stderr, "bench_nanoflann: %s\n", err);
        return NULL;
    }
    return nl;
}

template <int D> int compare(int reps)
{
    pst_cloud *c = scene_cloud(D);
    if (!c)
        return 1;
    size_t n = pst_cloud_size(c);
    double h = pst_cloud_h_max(c), r = kSupport * h;
    cloud_points pts{{pst_cloud_coord(c, 0), pst_cloud_coord(c, 1), D == 3 ? pst_cloud_coord(c, 2)
                                                                           : nullptr},
                     n};
    std::printf("%dD: %zu particles, radius %.4g (%.2f s0)\n", D, n, r, kSupport * 1.2);
    // Repetition by repetition, 1 then 2 threads, pstencil then nanoflann: each thread count is
    // measured beside the other, so that the 1 -> 2 thread ratios compare the same minutes.
    std::vector<double> t[2][2]; // [threads - 1][pstencil, nanoflann]
    int saved = omp_get_max_threads();
    for (int k = 0; k < reps; ++k)
        for (int nt = 1; nt <= 2; ++nt) {
            double tp;
            pst_nlist *nl = pstencil_list(c, nt, &tp);
            if (!nl)
                return 1;
            double t1 = omp_get_wtime();
            csr peer;
            nanoflann_list<D>(pts, r * r, peer);
            t[nt - 1][0].push_back(tp);
            t[nt - 1][1].push_back(omp_get_wtime() - t1);
            if (nt == 1 && k == 0) {
                int same = same_list(nl, peer, n);
                std::printf("  lists identical: %s (%.1f neighbours per particle)\n",
                            same ? "yes" : "NO", (double)pst_nlist_pairs(nl) / (double)n);
                if (!same)
                    return 1;
            }
            pst_nlist_destroy(nl);
        }
    double med[2][2];
    for (int nt = 1; nt <= 2; ++nt) {
        for (int side = 0; side < 2; ++side)
            med[nt - 1][side] = bench_median(t[nt - 1][side].data(), reps);
        std::printf("  %d thread%s: pstencil %.3f s, nanoflann %.3f s: ratio %.2f "
                    "(medians of %d)\n",
                    nt, nt > 1 ? "s" : " ", med[nt - 1][0], med[nt - 1][1],
                    med[nt - 1][1] / med[nt - 1][0], reps);
    }
    std::printf("  1 -> 2 threads: pstencil %.2fx, nanoflann %.2fx\n", med[0][0] / med[1][0],
                med[0][1] / med[1][1]);
    std::fflush(stdout);
    // pstencil's own scaling, its builds alternated with nothing between them. Beside nanoflann,
    // each build follows the peer's gigabyte of lists freed and handed back to the host (this
    // VM's free page reporting, docs/neighbours.md), and first touches of such pages slowed the
    // 2-thread build alone.
    std::vector<double> alone[2];
    for (int k = 0; k < reps; ++k)
        for (int nt = 1; nt <= 2; ++nt) {
            double tp;
            pst_nlist *nl = pstencil_list(c, nt, &tp);
            if (!nl)
                return 1;
            alone[nt - 1].push_back(tp);
            pst_nlist_destroy(nl);
        }
    omp_set_num_threads(saved);
    double a1 = bench_median(alone[0].data(), reps), a2 = bench_median(alone[1].data(), reps);
    std::printf("  1 -> 2 threads, pstencil alone (builds alternated): %.3f / %.3f s = %.2fx\n",
                a1, a2, a1 / a2);
    pst_cloud_destroy(c);
    return 0;
}

} // namespace

int main(int argc, char **argv)
{
    int reps = argc > 1 ? std::atoi(argv[1]) : 5;
    const char *dims = argc > 2 ? argv[2] : "23";
    if (reps < 1 || (std::strcmp(dims, "2") && std::strcmp(dims, "3") && std::strcmp(dims, "23"))) {
        std::fprintf(stderr, "usage: bench_nanoflann [repetitions] [3 | 2 | 23]\n");
        return 2;
    }
    int status = 0;
    if (std::strchr(dims, '3'))
        status |= compare<3>(reps);
    if (std::strchr(dims, '2'))
        status |= compare<2>(reps);
    return status;
}
