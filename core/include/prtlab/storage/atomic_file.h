#pragma once
// Nothing prtlab writes is ever half-written: output goes to "<path>.tmp.<pid>.<n>" and is renamed
// over the destination only after a successful close.
#include <filesystem>
#include <functional>
#include <ostream>
#include <span>
#include <string_view>

namespace prt {

/// Calls write(tmp_path) and renames tmp_path to path on success; removes it on failure.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& tmp)>& write);
/// Convenience: write bytes / text atomically (creates parent directories).
void write_bytes_atomically(const std::filesystem::path& path, std::span<const std::byte> bytes);
void write_text_atomically(const std::filesystem::path& path, std::string_view text);

}  // namespace prt
