#include "svd/abrdf_truncation.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>

#include "prtlab/base/error.h"

namespace prt::svd {

SvdState truncate_abrdfs(const Btf& btf, int rank) {
  const int v_count = btf.view_count(), m = btf.light_count(), texels = btf.texel_count();
  if (rank < 1 || rank > std::min(v_count, m))
    throw ParameterError(fmt::format(
        "material svd: rank {} is outside [1, min(V, M)] = [1, {}] for BTF '{}' (V = {} views, "
        "M = {} lights)",
        rank, std::min(v_count, m), btf.material(), v_count, m));
  SvdState s;
  s.mode = Mode::kAbrdf;
  s.sampling = sampling_of(btf);
  s.rank = rank;
  const std::size_t k = static_cast<std::size_t>(rank);
  const std::size_t view_stride = static_cast<std::size_t>(v_count) * k * 3;
  const std::size_t light_stride = k * static_cast<std::size_t>(m) * 3;
  s.view_factors.assign(static_cast<std::size_t>(texels) * view_stride, 0.0f);
  s.light_factors.assign(static_cast<std::size_t>(texels) * light_stride, 0.0f);
  // Per texel, so that the sums below run in texel order whatever the threads did.
  std::vector<double> discarded(static_cast<std::size_t>(texels), 0.0);
  std::vector<double> total(static_cast<std::size_t>(texels), 0.0);
  const std::span<const float> data = btf.data();
  tbb::parallel_for(0, texels, [&](int t) {
    Eigen::MatrixXd f(v_count, m);
    const std::size_t ts = static_cast<std::size_t>(t);
    float* vf = s.view_factors.data() + ts * view_stride;
    float* lf = s.light_factors.data() + ts * light_stride;
    for (int c = 0; c < 3; ++c) {
      for (int v = 0; v < v_count; ++v)
        for (int j = 0; j < m; ++j)
          f(v, j) = data[btf.offset(t, v, j) + static_cast<std::size_t>(c)];
      total[ts] += f.squaredNorm();
      const Eigen::BDCSVD<Eigen::MatrixXd> svd(f, Eigen::ComputeThinU | Eigen::ComputeThinV);
      const Eigen::VectorXd& sigma = svd.singularValues();
      for (Eigen::Index i = rank; i < sigma.size(); ++i) discarded[ts] += sigma[i] * sigma[i];
      const Eigen::MatrixXd& u = svd.matrixU();
      const Eigen::MatrixXd& w = svd.matrixV();
      for (int r = 0; r < rank; ++r) {
        for (int v = 0; v < v_count; ++v)
          vf[(static_cast<std::size_t>(v) * k + r) * 3 + c] = static_cast<float>(u(v, r));
        for (int j = 0; j < m; ++j)
          lf[(static_cast<std::size_t>(r) * m + j) * 3 + c] =
              static_cast<float>(sigma[r] * w(j, r));
      }
    }
  });
  for (int t = 0; t < texels; ++t) {
    s.discarded += discarded[static_cast<std::size_t>(t)];
    s.total += total[static_cast<std::size_t>(t)];
  }
  return s;
}

}  // namespace prt::svd
