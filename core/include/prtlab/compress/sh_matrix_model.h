#pragma once
// The pixel-basis transfer of per-vertex SH matrices, for the stored models (stored_model.h) of
// backends that relight an SH light into local SH coefficients (sh_biscale, cpca_sh). Such a
// backend stores per vertex p a matrix X_p (n_out x n_light, local coefficient i x light
// coefficient k); through its light projection and to_pixel_basis it acts on a pixel light
// L (L_q = radiance_q dOmega_q) as
//
//   T~_p = B X_p Y,   Y[k, q] = y_k(d_q)            (sh_project: l = Y L)
//                     B[j, i] = integral of y_i over cell j   (sh_cell_integrals)
//
// so its error against T is a property of the stored matrices alone, computed here without the
// relight:  ||T~ - T||_F^2 = sum_p ||T_p||^2 - 2 <T_p, B X_p Y> + tr(X_p^T G_B X_p G_Y),
// G_B = B^T B, G_Y = Y Y^T, the cross term summed over T's stored entries. All in double.
#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include "prtlab/compress/stored_model.h"
#include "prtlab/sphere/cubemap.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/transfer/transfer_matrix.h"

namespace prt {

class ShMatrixModel {
 public:
  /// Throws ParameterError for orders outside 1..kMaxShOrder.
  ShMatrixModel(const CubemapLayout& cubemap, const HemisphereGrid& grid, int light_order,
                int output_order);

  int light_dim() const { return n_light_; }
  int output_dim() const { return n_out_; }

  /// Fills `x` (n_out x n_light, row-major) with the matrix of `vertex`, in double.
  using MatrixOf = std::function<void(std::size_t vertex, std::span<double> x)>;

  /// ||T~ - T||_F / ||T||_F (0 when T = 0 and T~ = 0; ||T~||_F when T = 0), T~ given by
  /// `matrix` for each of T's vertices. TBB over vertices, deterministic.
  double relative_frobenius_error(const TransferMatrix& t, const MatrixOf& matrix) const;

  /// T~ L at the bins of `vertices` vertices for the light of `radiance` (its resolution must be
  /// the model's), and the magnitude |B| |X|_magnitude |Y| |L|, with `magnitude_of` giving the
  /// non-negative matrix that bounds the rounding of the backend's float relight (|X_p| itself,
  /// or the sum of |w_i| |X_i| over the factors X_p is stored as).
  ModelRadiance radiance(const Cubemap& radiance, std::size_t vertices, const MatrixOf& matrix,
                         const MatrixOf& magnitude_of) const;

 private:
  int resolution_, cells_, n_light_, n_out_;
  std::vector<double> y_;   // N x n_light: y_k(d_q)
  std::vector<double> b_;   // M x n_out: B
  std::vector<double> gb_;  // n_out x n_out: B^T B
  std::vector<double> gy_;  // n_light x n_light: Y Y^T
};

}  // namespace prt
