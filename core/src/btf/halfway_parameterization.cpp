#include "prtlab/btf/halfway_parameterization.h"

#include <glm/geometric.hpp>

#include "prtlab/sphere/hemisphere_grid.h"

namespace prt {

Vec3 halfway_f(Vec3 light, Vec3 view_clamped) {
  return glm::normalize(light + view_clamped);
}

BtfViewSamples halfway_samples(int half_side, Vec3 light, Vec3 view_clamped) {
  return btf_view_samples(half_side, halfway_f(light, view_clamped));
}

std::vector<Vec3> light_directions_f(int light_side) {
  const HemisphereGrid grid(light_side);
  std::vector<Vec3> out;
  out.reserve(static_cast<std::size_t>(grid.cell_count()));
  for (const Vec3d& d : grid.directions()) out.emplace_back(d);
  return out;
}

Eigen::SparseMatrix<double, Eigen::RowMajor> halfway_weights(int light_side, int view_side,
                                                             int half_side) {
  const std::vector<Vec3> lights = light_directions_f(light_side);
  const std::vector<Vec3> views = light_directions_f(view_side);
  const int m = light_side * light_side, v = view_side * view_side;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(m) * v * 4);
  for (int view = 0; view < v; ++view) {
    const Vec3 e = clamp_to_hemisphere(views[static_cast<std::size_t>(view)]);
    for (int j = 0; j < m; ++j) {
      const BtfViewSamples s = halfway_samples(half_side, lights[static_cast<std::size_t>(j)], e);
      for (int k = 0; k < 4; ++k)
        if (s.weight[k] != 0.0f) t.emplace_back(view * m + j, s.view[k], s.weight[k]);
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> w(m * v, half_side * half_side);
  w.setFromTriplets(t.begin(), t.end());  // repeated corners (at the grid edge) are summed
  return w;
}

std::pair<Vec3d, Vec3d> gshd_to_in_out(const Vec3d& h, const Vec3d& d) {
  Vec3d t(1.0, 0.0, 0.0);
  if (std::abs(h.x) > 0.999) t = Vec3d(0.0, 1.0, 0.0);
  t = glm::normalize(t - glm::dot(t, h) * h);
  const Vec3d b = glm::cross(h, t);
  const Vec3d in = glm::normalize(d.x * t + d.y * b + d.z * h);
  const Vec3d out = 2.0 * glm::dot(h, in) * h - in;
  return {in, out};
}

GshdResampling gshd_resampling(int light_side, int view_side, int half_side, int diff_side) {
  const HemisphereGrid half(half_side), diff(diff_side);
  const int m = light_side * light_side, hd = half.cell_count() * diff.cell_count();
  GshdResampling r;
  r.half_side = half_side;
  r.diff_side = diff_side;
  r.valid.assign(static_cast<std::size_t>(hd), 0);
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(hd) * 16);
  for (int a = 0; a < half.cell_count(); ++a)
    for (int b = 0; b < diff.cell_count(); ++b) {
      const auto [in, out] = gshd_to_in_out(half.direction(a), diff.direction(b));
      if (!(in.z > 0.0 && out.z > 0.0)) continue;
      const int row = a * diff.cell_count() + b;
      r.valid[static_cast<std::size_t>(row)] = 1;
      const BtfViewSamples li = btf_view_samples(light_side, Vec3(in));
      const BtfViewSamples vo = btf_view_samples(view_side, Vec3(out));
      for (int i = 0; i < 4; ++i)
        for (int o = 0; o < 4; ++o) {
          const double w = static_cast<double>(li.weight[i]) * vo.weight[o];
          if (w != 0.0) t.emplace_back(row, vo.view[o] * m + li.view[i], w);
        }
    }
  r.weights.resize(hd, m * view_side * view_side);
  r.weights.setFromTriplets(t.begin(), t.end());
  return r;
}

}  // namespace prt
