// Test-only: vmmlib's Tucker3 decomposition (Debian libvmmlib-dev 1.0, header-only, on LAPACK and
// CBLAS) as an implementation of truncated HOSVD and HOOI written by someone else, to check this
// backend's own N-mode SVD against. Include it only where deps.cmake defined PRTLAB_HAVE_VMMLIB,
// and before any other vmmlib header.
//
// Precision: vmmlib's LAPACK calls run in double (t3_hosvd's T_svd is double: dgesvd, dsyevx),
// but tensor3 hard-wires `typedef float T_blas` for every tensor-times-matrix product
// (multiply_*_bwd, full_tensor3_matrix_multiplication), and tucker3_tensor computes in float
// throughout (T_internal), so it is not used. That float path would put a floor of about 1e-7
// under every error, so the cores and reconstructions below are the products vmmlib forms, in its
// order, with its slice accessors and matrix::multiply in double. The one float step left is
// inside t3_hooi::als (its projections): HOOI's bases are only good to about 1e-7.
#pragma once

#include <cmath>
#include <cstddef>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>

namespace prt::srbf_cta::test::vmmlib_detail {
// LAPACK calls that reported failure since the last reset (vmmlib itself does not say; see below).
inline thread_local int lapack_failures = 0;
}  // namespace prt::srbf_cta::test::vmmlib_detail

// vmmlib's LAPACK binding is replaced, for three reasons:
//  - it includes <vmmlib/lapack/detail/{f2c,clapack}.h>, which Debian installs as
//    vmmlib/lipack/detail/, so vmmlib does not compile as installed;
//  - its f2c `integer` is `long`, but LAPACK's INTEGER is 32 bits: LAPACK writes half of each INFO,
//    vmmlib reads the stale upper half as a failure and zeroes the basis without a word;
//  - it asks dsyevx for an absolute eigenvalue tolerance of 1e-4. That picks bisection plus
//    inverse iteration, which on HOOI's rank-deficient covariances (I_n > R_m R_l) leaves
//    eigenvectors of the near-zero cluster unconverged, and vmmlib again zeroes the whole basis
//    mid-iteration (on 6x7x8 test tensors, depending on their scale, up to a quarter of HOOI runs
//    lost a basis or ended worse than their start). With tolerance 0 dsyevx takes the QR
//    algorithm for all eigenvalues (vmmlib always asks for all), which does not fail that way.
//  sgesvd/ssyevx are only here because vmmlib's float specialisations name them; T is double.
// So vmmlib's include guard is taken, and its unqualified calls from vmml::lapack find the
// forwarders below, which pass 32-bit integers, gfortran's hidden CHARACTER lengths, tolerance 0,
// and count failures. This also keeps f2c.h's abs/min/max macros out of the including file.
#ifdef __VMML__LAPACK_INCLUDES__HPP__
#error "vmmlib_tucker.h must come before any vmmlib header (it replaces vmmlib's LAPACK binding)"
#endif
#define __VMML__LAPACK_INCLUDES__HPP__
extern "C" {
void sgesvd_(const char* jobu, const char* jobvt, const int* m, const int* n, float* a,
             const int* lda, float* s, float* u, const int* ldu, float* vt, const int* ldvt,
             float* work, const int* lwork, int* info, std::size_t jobu_len,
             std::size_t jobvt_len);
void dgesvd_(const char* jobu, const char* jobvt, const int* m, const int* n, double* a,
             const int* lda, double* s, double* u, const int* ldu, double* vt, const int* ldvt,
             double* work, const int* lwork, int* info, std::size_t jobu_len,
             std::size_t jobvt_len);
void ssyevx_(const char* jobz, const char* range, const char* uplo, const int* n, float* a,
             const int* lda, const float* vl, const float* vu, const int* il, const int* iu,
             const float* abstol, int* m, float* w, float* z, const int* ldz, float* work,
             const int* lwork, int* iwork, int* ifail, int* info, std::size_t jobz_len,
             std::size_t range_len, std::size_t uplo_len);
void dsyevx_(const char* jobz, const char* range, const char* uplo, const int* n, double* a,
             const int* lda, const double* vl, const double* vu, const int* il, const int* iu,
             const double* abstol, int* m, double* w, double* z, const int* ldz, double* work,
             const int* lwork, int* iwork, int* ifail, int* info, std::size_t jobz_len,
             std::size_t range_len, std::size_t uplo_len);
}
namespace vmml::lapack {
using integer = int;  // becomes vmmlib's lapack_int
inline void prtlab_count_failure(const int* info) {
  if (*info != 0) ++prt::srbf_cta::test::vmmlib_detail::lapack_failures;
}
inline void sgesvd_(char* jobu, char* jobvt, int* m, int* n, float* a, int* lda, float* s,
                    float* u, int* ldu, float* vt, int* ldvt, float* work, int* lwork, int* info) {
  ::sgesvd_(jobu, jobvt, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork, info, 1, 1);
  prtlab_count_failure(info);
}
inline void dgesvd_(char* jobu, char* jobvt, int* m, int* n, double* a, int* lda, double* s,
                    double* u, int* ldu, double* vt, int* ldvt, double* work, int* lwork,
                    int* info) {
  ::dgesvd_(jobu, jobvt, m, n, a, lda, s, u, ldu, vt, ldvt, work, lwork, info, 1, 1);
  prtlab_count_failure(info);
}
inline void ssyevx_(char* jobz, char* range, char* uplo, int* n, float* a, int* lda, float* vl,
                    float* vu, int* il, int* iu, float* /*abstol*/, int* m, float* w, float* z,
                    int* ldz, float* work, int* lwork, int* iwork, int* ifail, int* info) {
  const float abstol = 0;
  ::ssyevx_(jobz, range, uplo, n, a, lda, vl, vu, il, iu, &abstol, m, w, z, ldz, work, lwork,
            iwork, ifail, info, 1, 1, 1);
  prtlab_count_failure(info);
}
inline void dsyevx_(char* jobz, char* range, char* uplo, int* n, double* a, int* lda, double* vl,
                    double* vu, int* il, int* iu, double* /*abstol*/, int* m, double* w,
                    double* z, int* ldz, double* work, int* lwork, int* iwork, int* ifail,
                    int* info) {
  const double abstol = 0;
  ::dsyevx_(jobz, range, uplo, n, a, lda, vl, vu, il, iu, &abstol, m, w, z, ldz, work, lwork,
            iwork, ifail, info, 1, 1, 1);
  prtlab_count_failure(info);
}
}  // namespace vmml::lapack

// tensor3 hands out its frontal slices as matrix references into one flat array, but vmmlib
// declares matrices 16-byte aligned, so every slice after an odd I1 * I2 is misaligned for its type
// (undefined behaviour; UBSan reports it, aligned vector loads could fault). Without the forced
// alignment a matrix needs only a double's.
#ifndef VMMLIB_DONT_FORCE_ALIGNMENT
#define VMMLIB_DONT_FORCE_ALIGNMENT
#endif
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-copy"
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wshadow"
#include <vmmlib/t3_hooi.hpp>
#include <vmmlib/t3_hosvd.hpp>
#include <vmmlib/tensor3.hpp>
#pragma GCC diagnostic pop

namespace prt::srbf_cta::test {

// x(i, j, k) is x[i + I1 * (j + I2 * k)], i < I1, j < I2, k < I3 (double).
struct VmmlibTuckerErrors {
  double hosvd = 0;  // ||X - X~||_F / ||X||_F, truncated HOSVD
  double hooi = 0;   // the same for HOOI (vmmlib's ALS, started from that HOSVD)
};

namespace vmmlib_detail {

template <std::size_t M, std::size_t N>
using Matrix = vmml::matrix<M, N, double>;
template <std::size_t I1, std::size_t I2, std::size_t I3>
using Tensor = vmml::tensor3<I1, I2, I3, double>;

// out = a x1 m1 x2 m2 x3 m3 through lateral, frontal and horizontal backward slices, as
// full_tensor3_matrix_multiplication does. vmmlib matrices hold their elements inline, hence the
// heap; vmmlib's slice accessors still pass one slice through the stack (transpose() returns by
// value), so I_a * I_b * 8 bytes must stay well under the stack size, as it must for als anyway.
template <std::size_t K1, std::size_t K2, std::size_t K3, std::size_t J1, std::size_t J2,
          std::size_t J3>
void multiply_modes(const Tensor<J1, J2, J3>& a, const Matrix<K1, J1>& m1,
                    const Matrix<K2, J2>& m2, const Matrix<K3, J3>& m3, Tensor<K1, K2, K3>& out) {
  auto t1 = std::make_unique<Tensor<K1, J2, J3>>();
  {
    auto in = std::make_unique<Matrix<J1, J3>>();
    auto res = std::make_unique<Matrix<K1, J3>>();
    for (std::size_t j2 = 0; j2 < J2; ++j2) {
      a.get_lateral_slice_bwd(j2, *in);
      res->multiply(m1, *in);
      t1->set_lateral_slice_bwd(j2, *res);
    }
  }
  auto t2 = std::make_unique<Tensor<K1, K2, J3>>();
  {
    auto in = std::make_unique<Matrix<J2, K1>>();
    auto res = std::make_unique<Matrix<K2, K1>>();
    for (std::size_t j3 = 0; j3 < J3; ++j3) {
      t1->get_frontal_slice_bwd(j3, *in);
      res->multiply(m2, *in);
      t2->set_frontal_slice_bwd(j3, *res);
    }
  }
  auto in = std::make_unique<Matrix<J3, K2>>();
  auto res = std::make_unique<Matrix<K3, K2>>();
  for (std::size_t k1 = 0; k1 < K1; ++k1) {
    t2->get_horizontal_slice_bwd(k1, *in);
    res->multiply(m3, *in);
    out.set_horizontal_slice_bwd(k1, *res);
  }
}

// core = x x_n U_n^T (optimal for orthonormal U_n; vmmlib's derive_core_orthogonal_bases), then
// back through the bases, and what is lost.
template <std::size_t I1, std::size_t I2, std::size_t I3, std::size_t R1, std::size_t R2,
          std::size_t R3>
double relative_error(const Tensor<I1, I2, I3>& x, const Matrix<I1, R1>& u1,
                      const Matrix<I2, R2>& u2, const Matrix<I3, R3>& u3) {
  auto u1t = std::make_unique<Matrix<R1, I1>>();
  auto u2t = std::make_unique<Matrix<R2, I2>>();
  auto u3t = std::make_unique<Matrix<R3, I3>>();
  u1.transpose_to(*u1t);
  u2.transpose_to(*u2t);
  u3.transpose_to(*u3t);
  auto core = std::make_unique<Tensor<R1, R2, R3>>();
  multiply_modes(x, *u1t, *u2t, *u3t, *core);
  auto approx = std::make_unique<Tensor<I1, I2, I3>>();
  multiply_modes(*core, u1, u2, u3, *approx);

  const double* xs = x.get_array_ptr();
  const double* ys = approx->get_array_ptr();
  double diff2 = 0, norm2 = 0;
  for (std::size_t n = 0; n < I1 * I2 * I3; ++n) {
    diff2 += (xs[n] - ys[n]) * (xs[n] - ys[n]);
    norm2 += xs[n] * xs[n];
  }
  return std::sqrt(diff2 / norm2);
}

inline void require_no_lapack_failure(const char* step) {
  if (lapack_failures != 0) {
    throw std::runtime_error(std::string("vmmlib_tucker_errors: a LAPACK call in vmmlib's ") +
                             step + " failed (vmmlib then zeroes that basis)");
  }
}

}  // namespace vmmlib_detail

// Truncated HOSVD (t3_hosvd::hosvd: SVD of each unfolding) and HOOI (t3_hooi::als, started from
// exactly those bases; vmmlib fixes its stopping rule: a change below 1e-4 in fit = 1 - error, or
// 10 sweeps), each reconstructed and its relative Frobenius error computed in double. HOOI never
// ends worse than the HOSVD it starts from, but for the ~1e-7 that als's float projections put
// into its bases: on a tensor of exact rank (R1, R2, R3) hosvd is ~1e-15 and hooi ~1e-7, and so is
// hooi - hosvd where the HOSVD is already optimal. A zero tensor gives NaN for both. Throws
// std::runtime_error where a LAPACK call inside vmmlib failed.
template <std::size_t I1, std::size_t I2, std::size_t I3, std::size_t R1, std::size_t R2,
          std::size_t R3>
VmmlibTuckerErrors vmmlib_tucker_errors(std::span<const double> x) {
  static_assert(R1 >= 1 && R2 >= 1 && R3 >= 1 && R1 <= I1 && R2 <= I2 && R3 <= I3,
                "vmmlib_tucker_errors: each rank lies in 1..its mode's size");
  // als decomposes projections of size I_n x (R_m R_l); vmmlib's SVD of one (compiled, though
  // als takes the eigen path) cannot keep more singular vectors than it has: no other ranks build.
  static_assert(R1 <= R2 * R3 && R2 <= R1 * R3 && R3 <= R1 * R2,
                "vmmlib_tucker_errors: each rank must be at most the product of the other two");
  namespace d = vmmlib_detail;
  using Hosvd = vmml::t3_hosvd<R1, R2, R3, I1, I2, I3, double>;
  using Hooi = vmml::t3_hooi<R1, R2, R3, I1, I2, I3, double>;
  if (x.size() != I1 * I2 * I3) {
    throw std::invalid_argument("vmmlib_tucker_errors: x holds " + std::to_string(x.size()) +
                                " values, not I1 * I2 * I3 = " + std::to_string(I1 * I2 * I3));
  }

  // tensor3 stores x(i, j, k) at i + I1 * (j + I2 * k) too. The copy is scaled to norm ~1 by a
  // power of two, exactly, so no error changes, and data near float's range limits still fits
  // vmmlib's float products.
  double norm2 = 0;
  for (double v : x) norm2 += v * v;
  int exponent = 0;
  std::frexp(std::sqrt(norm2), &exponent);
  const int shift = std::isfinite(norm2) && norm2 > 0 ? -exponent : 0;
  auto data = std::make_unique<d::Tensor<I1, I2, I3>>();
  double* dst = data->get_array_ptr();
  for (std::size_t n = 0; n < x.size(); ++n) dst[n] = std::ldexp(x[n], shift);

  d::lapack_failures = 0;
  auto u1 = std::make_unique<d::Matrix<I1, R1>>();
  auto u2 = std::make_unique<d::Matrix<I2, R2>>();
  auto u3 = std::make_unique<d::Matrix<I3, R3>>();
  Hosvd::hosvd(*data, *u1, *u2, *u3);
  d::require_no_lapack_failure("HOSVD");
  VmmlibTuckerErrors errors;
  errors.hosvd = d::relative_error(*data, *u1, *u2, *u3);

  // als calls its init functor on its own bases; handing it the HOSVD bases above (rather than
  // t3_hooi::init_hosvd, which recomputes them from covariance eigenvectors) starts HOOI from the
  // decomposition whose error is reported as hosvd.
  struct StartFromHosvd {
    const d::Matrix<I1, R1>* u1;
    const d::Matrix<I2, R2>* u2;
    const d::Matrix<I3, R3>* u3;
    void operator()(const d::Tensor<I1, I2, I3>&, d::Matrix<I1, R1>& a, d::Matrix<I2, R2>& b,
                    d::Matrix<I3, R3>& c) const {
      a = *u1;
      b = *u2;
      c = *u3;
    }
  };
  auto v1 = std::make_unique<d::Matrix<I1, R1>>();
  auto v2 = std::make_unique<d::Matrix<I2, R2>>();
  auto v3 = std::make_unique<d::Matrix<I3, R3>>();
  auto core = std::make_unique<d::Tensor<R1, R2, R3>>();  // als's own, float-accurate: unused
  Hooi::als(*data, *v1, *v2, *v3, *core, StartFromHosvd{u1.get(), u2.get(), u3.get()});
  d::require_no_lapack_failure("HOOI");
  errors.hooi = d::relative_error(*data, *v1, *v2, *v3);
  return errors;
}

}  // namespace prt::srbf_cta::test
