// The stored model of backend `srbf_cta` (stored_model.h): per vertex its M x n_t transfer
// coefficients rebuilt from the stored factors, U K_x U_c^T with K_x = refold(W_x V_c), in double,
// times the light step's L'. The relight contracts the other way (L' into each cluster's light
// basis, its duals and the view basis first, then each vertex's weights), so the two meet only
// in the stored arrays and in L'.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>

#include "srbf_cta/srbf_cta.h"

namespace prt::srbf_cta {

ModelRadiance SrbfCtaTransfer::model_radiance(const Cubemap& radiance) const {
  using MatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using MatD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Eigen::MatrixXd light = light_products(radiance);  // n_t x 3
  const Eigen::MatrixXd light_abs = light.cwiseAbs();
  const Eigen::Index r1 = a_.rank_view, r2 = a_.rank_light, r3 = a_.rank_vertex,
                     nt = a_.srbf_count, mm = a_.local_count;
  const MatD u = Eigen::Map<const MatF>(a_.view_basis.data(), mm, r1).cast<double>();
  const MatD u_abs = u.cwiseAbs();
  ModelRadiance out;
  out.values.assign(a_.vertices * static_cast<std::size_t>(mm), Vec3d(0.0));
  out.magnitude.assign(out.values.size(), Vec3d(0.0));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, a_.vertices, 16), [&](const auto& r) {
    for (std::size_t x = r.begin(); x != r.end(); ++x) {
      const std::size_t c = a_.ids[x];
      const MatD uc =
          Eigen::Map<const MatF>(a_.light_bases.data() + c * static_cast<std::size_t>(nt * r2), nt,
                                 r2)
              .cast<double>();
      const MatD v =
          Eigen::Map<const MatF>(a_.duals.data() + c * static_cast<std::size_t>(r3 * r1 * r2), r3,
                                 r1 * r2)
              .cast<double>();
      const Eigen::RowVectorXd w =
          Eigen::Map<const Eigen::RowVectorXf>(a_.weights.data() + x * static_cast<std::size_t>(r3),
                                               r3)
              .cast<double>();
      const Eigen::RowVectorXd kv = w * v, kv_abs = w.cwiseAbs() * v.cwiseAbs();
      const MatD k = Eigen::Map<const MatD>(kv.data(), r1, r2),
                 k_abs = Eigen::Map<const MatD>(kv_abs.data(), r1, r2);
      const MatD rows = u * k * uc.transpose();  // M x n_t: the vertex's transfer coefficients
      const MatD value = rows * light;
      const MatD size = u_abs * (k_abs * (uc.cwiseAbs().transpose() * light_abs));
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
