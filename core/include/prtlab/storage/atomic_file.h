#pragma once
// Nothing prtlab writes is ever half-written: output goes to "<path>.tmp.<pid>.<n>" and is renamed
// over the destination only after a successful close. A process stopped while writing leaves its
// temporary behind; SIGINT and SIGTERM remove it (remove_temporaries_on_signal), and for what
// nothing can catch (SIGKILL, a crash, a power cut) the next write of that destination, and the
// stage cache's first use of a stage folder, remove temporaries whose process is gone.
#include <filesystem>
#include <functional>
#include <ostream>
#include <span>
#include <string_view>

namespace prt {

/// Calls write(tmp_path) and renames tmp_path to path on success; removes it on failure.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& tmp)>& write);
/// A file of a set written all or nothing: write(tmp) fills the temporary.
struct PendingFile {
  std::filesystem::path path;
  std::function<void(const std::filesystem::path& tmp)> write;
};
/// Writes every file to its temporary and renames them into place only after all succeeded:
/// a command writing an image and its preview leaves neither when one of them fails.
void write_files_atomically(std::span<const PendingFile> files);
/// Convenience: write bytes / text atomically (creates parent directories).
void write_bytes_atomically(const std::filesystem::path& path, std::span<const std::byte> bytes);
void write_text_atomically(const std::filesystem::path& path, std::string_view text);

/// This machine's name as temporaries carry it: the host name with every character other than
/// a letter, a digit or '-' replaced by '_'.
const std::string& atomic_temporary_host();
/// True for a name "<anything>.tmp.<host>.<pid>.<n>" as write_file_atomically makes (or
/// "<anything>.tmp.<pid>.<n>", host empty, as older versions made); sets *pid and *host.
bool is_atomic_temporary_name(const std::string& filename, long* pid = nullptr,
                              std::string* host = nullptr);
/// Removes the temporaries in `dir` (not recursive) left by processes of this host that no
/// longer run. Returns how many it removed. A temporary named for another host is left alone
/// whatever its pid: on a folder shared by the nodes of a cluster, this host's process table
/// says nothing of another node's processes (an older name without a host counts as this
/// host's).
std::size_t remove_stale_temporaries(const std::filesystem::path& dir);
/// remove_stale_temporaries(dir) the first time this process asks for `dir`, nothing after: a
/// folder of thousands of cache entries is listed once, not on every write. Writes and the stage
/// cache call it.
void remove_stale_temporaries_once(const std::filesystem::path& dir);
/// Installs SIGINT and SIGTERM handlers that unlink this process's temporaries in flight and
/// then die of the signal as before. Idempotent; the CLI calls it first thing.
void remove_temporaries_on_signal();

}  // namespace prt
