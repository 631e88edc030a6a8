#pragma once
// The orthonormal two-dimensional non-standard Haar transform of a cubemap, face by face
// (R a power of two). The layout of a face's R x R coefficients is GSL's
// (gsl_wavelet2d_nstransform with gsl_wavelet_haar): at each level, from size s = R down to 2,
// one Haar step on every row of the s x s top-left block (sums to columns [0, s/2), differences
// to [s/2, s)), then on every column of it (sums to rows [0, s/2), differences to [s/2, s)).
// A step maps a pair (a, b), a the lower index, to ((a + b) / sqrt 2, (a - b) / sqrt 2).
//
// Coefficient (x, y) of a face, in pixel index k = face * R * R + y * R + x like the cubemap:
//   (0, 0)             the face's scaling coefficient: sum of the face's pixels / R
//   otherwise          s = the power of two with s <= max(x, y) < 2 s; the support is the
//                      b x b pixel block at ((x mod s) b, (y mod s) b), b = R / s, and the basis
//                      function is +-1/b on it: x >= s splits the block's columns (+ left half,
//                      - right half), y >= s its rows (+ top half, - bottom half), both: the
//                      product of the two signs.
// The transform is orthonormal: Parseval holds, and dot products are kept, so
// t . L = W t . W L for a transfer row t and a light L.
#include <cstdint>
#include <span>
#include <vector>

#include "prtlab/sphere/cubemap.h"

namespace prt::haar {

/// Whether the Haar transform is defined for face resolution R (a power of two, >= 1).
bool is_power_of_two(int resolution);

/// The support of the basis function at face coefficient (x, y).
struct HaarSupport {
  int x0 = 0, y0 = 0;    ///< top-left pixel of the block
  int size = 1;          ///< b: the block is b x b pixels
  bool split_x = false;  ///< columns: + left half, - right half
  bool split_y = false;  ///< rows: + top half, - bottom half
};
/// The support of coefficient (x, y) of a face of resolution R (both < R).
HaarSupport haar_support(int resolution, int x, int y);

/// Forward transform of one R x R face, in place (row-major, y * R + x); `scratch` holds R.
void forward_face(std::span<double> face, int resolution, std::span<double> scratch);
/// Inverse of forward_face.
void inverse_face(std::span<double> face, int resolution, std::span<double> scratch);

/// Every face of an N = 6 R^2 cubemap vector (pixel order of CubemapLayout).
void forward_cubemap(std::span<double> values, int resolution);
void inverse_cubemap(std::span<double> values, int resolution);

/// Per coefficient k (the cubemap's index order): the solid angle of its support, the sum of the
/// exact solid angles of the pixels in it. Throws ParameterError unless R is a power of two.
std::vector<double> support_solid_angles(const CubemapLayout& layout);

/// FLOPs of the fast transform of one N-vector (one colour channel): per 2 x 2 group of each
/// level 8 additions and 4 multiplications by 1/2, (R^2 - 1) / 3 groups per face.
double transform_flops(int resolution);

}  // namespace prt::haar
