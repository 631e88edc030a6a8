#pragma once
// A clustered tensor approximation in progress, as a prtlab archive: the CTA saves its state
// after the initialisation and after every clustering iteration, so that a run killed part-way
// (a long compression on the chair, a job past its time limit) continues where it was instead
// of starting again. The state is stored in the stage cache under a key that hashes the tensor
// and every option the model depends on; the finished compression removes it.
#include <filesystem>
#include <optional>

#include "prtlab/storage/archive.h"
#include "prtlab/storage/content_hash.h"
#include "srbf_cta/clustered_tensor.h"

namespace prt::srbf_cta {

/// The key of a run's checkpoint: the tensor's values and shape, the CTA options that shape the
/// model, and the format version.
Hash128 cta_checkpoint_key(const TensorView& t, const CtaOptions& o);

ArchiveWriter save_cta_checkpoint(const CtaCheckpoint& c);
/// Throws InputError naming the archive when a section is missing or inconsistent.
CtaCheckpoint load_cta_checkpoint(const ArchiveReader& r);

/// Where a run's checkpoints live: the stage cache's "srbf_cta-checkpoint" folder.
std::filesystem::path cta_checkpoint_path(const Hash128& key);

/// The checkpoint at `path` when there is one and it loads; a file that does not is reported
/// (named warning) and ignored.
std::optional<CtaCheckpoint> read_cta_checkpoint(const std::filesystem::path& path);

}  // namespace prt::srbf_cta
