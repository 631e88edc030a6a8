// Fuzz target: the archive reader (archive.h). Each input is read twice: as it is (the envelope
// checks: magic, length, trailer, checksum) and with its envelope made valid
// (with_valid_envelope), which lets mutations reach the header, metadata and section parsers.
// Every section is then viewed as its own type and, where it could be one, as an index
// section; a transfer-matrix archive also goes through load_transfer (transfer_io.h).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "fuzz_support.h"
#include "prtlab/storage/archive.h"
#include "prtlab/transfer/transfer_io.h"

namespace {

template <typename T>
void touch(const prt::ArchiveReader& r, const prt::SectionInfo& s) {
  const auto v = r.view<T>(s.name, s.count);
  // Reading the first and last element checks that the view lies inside the buffer.
  volatile T sink{};
  if (!v.empty()) sink = static_cast<T>(v.front() + v.back());
  (void)sink;
}

void read_all(const prt::ArchiveReader& r) {
  using prt::ElementType;
  for (const prt::SectionInfo& s : r.sections()) {
    switch (s.type) {
      case ElementType::kUInt8:
        touch<std::uint8_t>(r, s);
        break;
      case ElementType::kInt8:
        touch<std::int8_t>(r, s);
        break;
      case ElementType::kUInt16:
        touch<std::uint16_t>(r, s);
        (void)r.indices(s.name);
        break;
      case ElementType::kInt16:
        touch<std::int16_t>(r, s);
        break;
      case ElementType::kUInt32:
        touch<std::uint32_t>(r, s);
        (void)r.indices(s.name);
        break;
      case ElementType::kInt32:
        touch<std::int32_t>(r, s);
        break;
      case ElementType::kUInt64:
        touch<std::uint64_t>(r, s);
        break;
      case ElementType::kInt64:
        touch<std::int64_t>(r, s);
        break;
      case ElementType::kFloat32:
        touch<float>(r, s);
        break;
      case ElementType::kFloat64:
        touch<double>(r, s);
        break;
    }
  }
  if (r.meta().contains("written_by")) (void)r.meta().dump();
  if (r.kind() == prt::kTransferArchiveKind) (void)prt::load_transfer(r);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto raw = std::as_bytes(std::span(data, size));
  prt::fuzz::run([&] { read_all(prt::ArchiveReader::from_bytes(raw, "fuzz-input.prt")); });
  const auto fixed = prt::fuzz::with_valid_envelope(std::span(data, size));
  return prt::fuzz::run(
      [&] { read_all(prt::ArchiveReader::from_bytes(fixed, "fuzz-input-fixed.prt")); });
}
