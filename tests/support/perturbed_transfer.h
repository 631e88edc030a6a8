#pragma once
// A compressed transfer whose C++ relight is off by 1 %: it wraps any CompressedTransfer and
// forwards everything (storage, declarations, light projection, device path, save, and the
// stored model when the wrapped transfer has one) except relight(), whose every value it changes
// by a relative 1 %. The accuracy checks must reject it (lossy_perturbation_test.cpp): a backend
// whose relight drifts from what its stored arrays imply by that much is broken.
#include <memory>
#include <stdexcept>

#include "prtlab/compress/compressor.h"
#include "prtlab/compress/stored_model.h"

namespace prt::testing {

enum class Perturbation {
  kScale,        ///< every value times 1.01
  kAlternating,  ///< value i times 1 + 0.01 (-1)^i: no common scale to absorb it
};

inline const char* to_string(Perturbation p) {
  return p == Perturbation::kScale ? "scale" : "alternating";
}

class PerturbedTransfer : public CompressedTransfer {
 public:
  PerturbedTransfer(std::shared_ptr<const CompressedTransfer> inner, Perturbation p)
      : inner_(std::move(inner)), p_(p) {}

  const CompressedTransfer& inner() const { return *inner_; }

  std::string backend() const override { return inner_->backend(); }
  StorageReport storage() const override { return inner_->storage(); }
  double flops_per_relight() const override { return inner_->flops_per_relight(); }
  double declared_error_bound() const override { return inner_->declared_error_bound(); }
  ErrorNorm declared_error_norm() const override { return inner_->declared_error_norm(); }
  std::optional<double> expected_frobenius_error() const override {
    return inner_->expected_frobenius_error();
  }
  RadianceBasis output_basis() const override { return inner_->output_basis(); }
  LightCoeffs project_light(const Cubemap& radiance) const override {
    return inner_->project_light(radiance);
  }
  void relight(const LightCoeffs& light, LocalRadiance& out) const override {
    inner_->relight(light, out);
    for (std::size_t i = 0; i < out.values.size(); ++i) {
      const float f = p_ == Perturbation::kScale || i % 2 == 0 ? 1.01f : 0.99f;
      out.values[i] *= f;
    }
  }
  std::unique_ptr<DeviceRelighter> upload(ClContext& context,
                                          const ParamSet& device_options) const override {
    return inner_->upload(context, device_options);
  }
  void save(ArchiveWriter& archive) const override { inner_->save(archive); }

 private:
  std::shared_ptr<const CompressedTransfer> inner_;
  Perturbation p_;
};

/// The same, also offering the wrapped transfer's stored model (unperturbed).
class PerturbedModelTransfer final : public PerturbedTransfer, public StoredModel {
 public:
  PerturbedModelTransfer(std::shared_ptr<const CompressedTransfer> inner, Perturbation p)
      : PerturbedTransfer(std::move(inner), p), model_(stored_model(this->inner())) {
    if (model_ == nullptr) throw std::invalid_argument("the wrapped transfer has no stored model");
  }
  ModelRadiance model_radiance(const Cubemap& radiance) const override {
    return model_->model_radiance(radiance);
  }

 private:
  const StoredModel* model_;
};

/// `inner` with its relight perturbed by 1 %, offering a stored model exactly when `inner` does.
inline std::unique_ptr<CompressedTransfer> perturbed(
    std::shared_ptr<const CompressedTransfer> inner, Perturbation p) {
  if (stored_model(*inner) != nullptr)
    return std::make_unique<PerturbedModelTransfer>(std::move(inner), p);
  return std::make_unique<PerturbedTransfer>(std::move(inner), p);
}

}  // namespace prt::testing
