// Replays inputs through a fuzz target without libFuzzer, for the normal test suite: every
// regular file under each argument (a file or a folder, recursively, in sorted order) goes
// through LLVMFuzzerTestOneInput once. A crash or sanitizer report ends the process, which
// fails the test; the file being run is printed first so the failing input is named.
//
// Usage: fuzz_replay_<target> <file or folder>...
// A folder that does not exist counts as empty (a target without regression inputs yet).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 2) {
    std::cerr << "usage: " << argv[0] << " <file or folder>...\n";
    return 2;
  }
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg = argv[i];
    if (fs::is_regular_file(arg)) {
      files.push_back(arg);
    } else if (fs::is_directory(arg)) {
      for (const auto& entry : fs::recursive_directory_iterator(arg))
        if (entry.is_regular_file()) files.push_back(entry.path());
    } else if (fs::exists(arg)) {
      std::cerr << arg.string() << ": neither a file nor a folder\n";
      return 2;
    }
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    std::ifstream in(file, std::ios::binary);
    const std::vector<char> bytes{std::istreambuf_iterator<char>(in),
                                  std::istreambuf_iterator<char>()};
    if (!in.eof() && in.fail()) {
      std::cerr << file.string() << ": cannot be read\n";
      return 1;
    }
    std::cerr << "replay " << file.string() << " (" << bytes.size() << " bytes)\n";
    // A copy of exactly the input's size, so a read past its end is a heap overflow that
    // AddressSanitizer reports, as under libFuzzer.
    std::vector<std::uint8_t> data(bytes.begin(), bytes.end());
    LLVMFuzzerTestOneInput(data.data(), data.size());
  }
  std::cerr << "replayed " << files.size() << " input" << (files.size() == 1 ? "" : "s") << "\n";
  return 0;
}
