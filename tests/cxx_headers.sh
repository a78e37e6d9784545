#!/usr/bin/env bash
# Every public header compiles alone as C++17 and C++20 (-Wall -Wextra -Wpedantic -Werror), and
# the values a C++ caller passes between calls have the enum types, so it needs no cast.
# Usage: cxx_headers.sh INCLUDE_DIR CXX
set -euo pipefail
inc=$1
cxx=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$inc"
for h in pstencil.h pstencil_expr.h pstencil/*.h; do
  printf '#include <%s>\nint main() { return 0; }\n' "$h" > "$work/alone.cpp"
  for std in 17 20; do
    "$cxx" -std=c++$std -Wall -Wextra -Wpedantic -Werror -I"$inc" -c "$work/alone.cpp" \
      -o "$work/alone.o" || { echo "cxx_headers: $h fails as C++$std" >&2; exit 1; }
  done
done
cat > "$work/types.cpp" <<'CPP'
#include <pstencil.h>
#include <type_traits>
#define SAME(a, b) static_assert(std::is_same<a, b>::value, #a " is not " #b)
SAME(decltype(pst_op_opts::kernel), pst_kernel);
SAME(decltype(pst_op_opts::gradient), pst_gradient);
SAME(decltype(pst_op_opts::on_degenerate), pst_on_degenerate);
SAME(decltype(pst_op_opts::mobility_mean), pst_mobility_mean);
SAME(decltype(pst_op_store_opts::precision), pst_store_precision);
SAME(decltype(pst_solve_opts::solver), pst_solver);
SAME(decltype(pst_solve_opts::precond), pst_precond);
SAME(decltype(pst_solve_opts::amg_source), pst_amg_source);
SAME(decltype(pst_solve_opts::amg_coarsen), pst_amg_coarsen);
SAME(decltype(pst_solve_opts::amg_interp), pst_amg_interp);
SAME(decltype(pst_solve_result::stop), pst_stop_reason);
SAME(decltype(pst_solve_result::solver), pst_solver);
SAME(decltype(pst_krylov_stats::solver), pst_solver);
SAME(decltype(pst_krylov_stats::precond), pst_precond);
SAME(decltype(pst_kernel_from_name("cubic")), pst_kernel);
SAME(decltype(pst_scheme_default_kernel("qsfdi")), pst_kernel);
SAME(decltype(pst_op_kernel(nullptr)), pst_kernel);
SAME(decltype(pst_op_store_precision(nullptr)), pst_store_precision);
SAME(decltype(pst_norm_from_name("rel_l2")), pst_norm);
static_assert(PST_KERNEL_DEFAULT == -1 && PST_KERNEL_UNKNOWN == -1, "sentinels");
int main() { return pst_kernel_support(pst_scheme_default_kernel("qsfdi")) > 0 ? 0 : 1; }
CPP
"$cxx" -std=c++17 -Wall -Wextra -Wpedantic -Werror -I"$inc" -c "$work/types.cpp" -o "$work/t.o"
echo "cxx_headers: every public header compiles as C++17 and C++20; the API's enums are typed"
