// The stored model of backend `srbf_cta` (stored_model.h): per vertex its core K_x =
// refold(W_x V_c) rebuilt from the stored factors, in double, and T~_x L = U K_x (U_c^T L'). The
// relight never forms K_x: it contracts L' with every dual of a cluster and the view basis first
// and applies each vertex's weights last, in float.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <vector>

#include "srbf_cta/srbf_cta.h"

namespace prt::srbf_cta {

ModelRadiance SrbfCtaTransfer::model_radiance(const Cubemap& radiance) const {
  using MatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using MatD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::MatrixXd light = light_products(radiance);  // n_t x 3
  const Eigen::MatrixXd light_abs = light.cwiseAbs();
  const Eigen::Index r1 = a_.rank_view, r2 = a_.rank_light, r3 = a_.rank_vertex, nt = a_.srbf_count,
                     mm = a_.local_count;
  const MatD u = Eigen::Map<const MatF>(a_.view_basis.data(), mm, r1).cast<double>();
  const MatD u_abs = u.cwiseAbs();
  ModelRadiance out;
  out.values.assign(a_.vertices * static_cast<std::size_t>(mm), Vec3d(0.0));
  out.magnitude.assign(out.values.size(), Vec3d(0.0));
  // Per cluster U_c^T L' and |U_c|^T |L'| (R2 x 3).
  const std::size_t clusters = a_.clusters();
  std::vector<MatD> projected(clusters), projected_abs(clusters);
  for (std::size_t c = 0; c < clusters; ++c) {
    const MatD uc = Eigen::Map<const MatF>(
                        a_.light_bases.data() + c * static_cast<std::size_t>(nt * r2), nt, r2)
                        .cast<double>();
    projected[c] = uc.transpose() * light;
    projected_abs[c] = uc.cwiseAbs().transpose() * light_abs;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a_.vertices, 16), [&](const auto& r) {
    for (std::size_t x = r.begin(); x != r.end(); ++x) {
      const std::size_t c = a_.ids[x];
      const MatD v = Eigen::Map<const MatF>(
                         a_.duals.data() + c * static_cast<std::size_t>(r3 * r1 * r2), r3, r1 * r2)
                         .cast<double>();
      const Eigen::RowVectorXd w = Eigen::Map<const Eigen::RowVectorXf>(
                                       a_.weights.data() + x * static_cast<std::size_t>(r3), r3)
                                       .cast<double>();
      const Eigen::RowVectorXd kv = w * v, kv_abs = w.cwiseAbs() * v.cwiseAbs();
      const MatD k = Eigen::Map<const MatD>(kv.data(), r1, r2),
                 k_abs = Eigen::Map<const MatD>(kv_abs.data(), r1, r2);
      const MatD value = u * (k * projected[c]);
      const MatD size = u_abs * (k_abs * projected_abs[c]);
      for (Eigen::Index m = 0; m < mm; ++m) {
        const std::size_t row = x * static_cast<std::size_t>(mm) + static_cast<std::size_t>(m);
        out.values[row] = Vec3d(value(m, 0), value(m, 1), value(m, 2));
        out.magnitude[row] = Vec3d(size(m, 0), size(m, 1), size(m, 2));
      }
    }
  });
  return out;
}

}  // namespace prt::srbf_cta
