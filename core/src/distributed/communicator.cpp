#include "prtlab/distributed/communicator.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <thread>

#include "prtlab/base/error.h"

#ifdef PRTLAB_HAVE_MPI
// The C API only: Open MPI's deprecated C++ bindings are not used (and do not compile
// warning-free).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace prt {
namespace {

// Messages longer than MPI's int count go in pieces of this many bytes.
constexpr std::size_t kPiece = std::size_t{1} << 30;
constexpr int kFirstTag = 100, kLastTag = 30000;  // MPI guarantees tags up to 32767

int env_int(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : -1;
}

// What the starter told the process about the group (-1: not started by one).
int launched_size() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"})
    if (const int n = env_int(name); n >= 1) return n;
  if (std::getenv("PMIX_RANK") || std::getenv("PMI_RANK")) return 0;  // size unknown
  return -1;
}

#ifdef PRTLAB_HAVE_MPI
void check(int code, const char* what) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw std::runtime_error(fmt::format("MPI {} failed: {}", what, std::string(text, length)));
}
// Waits for a request without spinning: a rank waiting for another (the root still tracing, still
// preparing a scene) leaves the core to the ranks and threads that work. The sleep grows to 1 ms.
void wait(MPI_Request& request, const char* what) {
  int flag = 0;
  auto nap = std::chrono::microseconds(20);
  for (;;) {
    check(MPI_Test(&request, &flag, MPI_STATUS_IGNORE), what);
    if (flag) return;
    std::this_thread::sleep_for(nap);
    nap = std::min(nap * 2, std::chrono::microseconds(1000));
  }
}
#endif

}  // namespace

Communicator& Communicator::world() {
  static Communicator instance;
  return instance;
}

bool mpi_available() {
#ifdef PRTLAB_HAVE_MPI
  return true;
#else
  return false;
#endif
}

bool launched_by_mpi() {
  return launched_size() >= 0;
}

namespace {
std::atomic<Communicator*> g_collective{nullptr};
}  // namespace

CollectiveScope::CollectiveScope(Communicator& comm) : previous_(g_collective.exchange(&comm)) {}
CollectiveScope::~CollectiveScope() {
  g_collective.store(previous_);
}
Communicator* collective() {
  return g_collective.load();
}

std::string Communicator::description() const {
  if (!mpi_) return "1 process";
#ifdef PRTLAB_HAVE_MPI
  char version[MPI_MAX_LIBRARY_VERSION_STRING];
  int length = 0;
  MPI_Get_library_version(version, &length);
  std::string v(version, static_cast<std::size_t>(length));
  if (const auto comma = v.find(','); comma != std::string::npos) v.resize(comma);
  return fmt::format("{} MPI rank{} ({})", size_, size_ == 1 ? "" : "s", v);
#else
  return "1 process";
#endif
}

int Communicator::fresh_tag() {
  const int tag = next_tag_;
  next_tag_ = next_tag_ >= kLastTag ? kFirstTag : next_tag_ + 1;
  return tag;
}

#ifdef PRTLAB_HAVE_MPI

void Communicator::barrier() {
  if (!mpi_) return;
  MPI_Request r;
  check(MPI_Ibarrier(MPI_COMM_WORLD, &r), "barrier");
  wait(r, "barrier");
}

std::vector<std::uint8_t> Communicator::broadcast(std::vector<std::uint8_t> bytes, int root) {
  if (!mpi_ || size_ == 1) return bytes;
  std::uint64_t n = bytes.size();
  MPI_Request r;
  check(MPI_Ibcast(&n, 1, MPI_UINT64_T, root, MPI_COMM_WORLD, &r), "broadcast");
  wait(r, "broadcast");
  bytes.resize(n);
  for (std::size_t at = 0; at < n; at += kPiece) {
    const auto piece = static_cast<int>(std::min<std::uint64_t>(kPiece, n - at));
    check(MPI_Ibcast(bytes.data() + at, piece, MPI_BYTE, root, MPI_COMM_WORLD, &r), "broadcast");
    wait(r, "broadcast");
  }
  if (rank_ == root) bytes_sent_ += (n + 8) * static_cast<std::uint64_t>(size_ - 1);
  return bytes;
}

void Communicator::send(int to, int tag, std::span<const std::uint8_t> bytes) {
  PRT_CHECK(mpi_, "Communicator::send on one process");
  const std::uint64_t n = bytes.size();
  MPI_Request r;
  check(MPI_Isend(&n, 1, MPI_UINT64_T, to, tag, MPI_COMM_WORLD, &r), "send");
  wait(r, "send");
  for (std::size_t at = 0; at < n; at += kPiece) {
    const auto piece = static_cast<int>(std::min<std::uint64_t>(kPiece, n - at));
    check(MPI_Isend(bytes.data() + at, piece, MPI_BYTE, to, tag, MPI_COMM_WORLD, &r), "send");
    wait(r, "send");
  }
  bytes_sent_ += n + 8;
}

std::vector<std::uint8_t> Communicator::receive(int from, int tag) {
  PRT_CHECK(mpi_, "Communicator::receive on one process");
  std::uint64_t n = 0;
  MPI_Request r;
  check(MPI_Irecv(&n, 1, MPI_UINT64_T, from, tag, MPI_COMM_WORLD, &r), "receive");
  wait(r, "receive");
  std::vector<std::uint8_t> bytes(n);
  for (std::size_t at = 0; at < n; at += kPiece) {
    const auto piece = static_cast<int>(std::min<std::uint64_t>(kPiece, n - at));
    check(MPI_Irecv(bytes.data() + at, piece, MPI_BYTE, from, tag, MPI_COMM_WORLD, &r), "receive");
    wait(r, "receive");
  }
  return bytes;
}

bool Communicator::try_receive(int tag, int& from, std::vector<std::uint8_t>& bytes) {
  PRT_CHECK(mpi_, "Communicator::try_receive on one process");
  int flag = 0;
  MPI_Status status;
  check(MPI_Iprobe(MPI_ANY_SOURCE, tag, MPI_COMM_WORLD, &flag, &status), "probe");
  if (!flag) return false;
  from = status.MPI_SOURCE;
  bytes = receive(from, tag);
  return true;
}

std::vector<std::vector<std::uint8_t>> Communicator::gather(std::span<const std::uint8_t> bytes,
                                                            int root) {
  std::vector<std::vector<std::uint8_t>> out;
  if (!mpi_ || size_ == 1) {
    out.emplace_back(bytes.begin(), bytes.end());
    return out;
  }
  const int tag = fresh_tag();
  if (rank_ != root) {
    send(root, tag, bytes);
    return out;
  }
  out.resize(static_cast<std::size_t>(size_));
  for (int r = 0; r < size_; ++r)
    out[static_cast<std::size_t>(r)] =
        r == root ? std::vector<std::uint8_t>(bytes.begin(), bytes.end()) : receive(r, tag);
  return out;
}

bool Communicator::any(bool flag) {
  if (!mpi_ || size_ == 1) return flag;
  int in = flag ? 1 : 0, out = 0;
  MPI_Request r;
  check(MPI_Iallreduce(&in, &out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD, &r), "allreduce");
  wait(r, "allreduce");
  bytes_sent_ += sizeof(int);
  return out != 0;
}

DistributedSession::DistributedSession(int& argc, char**& argv) {
  const int size = launched_size();
  if (size < 0) return;  // not launched by an MPI starter: one process, MPI untouched
  int provided = 0;
  check(MPI_Init_thread(&argc, &argv, MPI_THREAD_MULTIPLE, &provided), "init");
  Communicator& w = Communicator::world();
  w.mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &w.rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &w.size_);
  if (w.size_ > 1 && provided < MPI_THREAD_MULTIPLE) {
    if (w.rank_ == 0)
      std::fputs(
          "error: this MPI library does not provide MPI_THREAD_MULTIPLE, which prtlab's work "
          "queue needs (the root hands out work from a thread of its own)\n",
          stderr);
    abort(1);
  }
}

DistributedSession::~DistributedSession() {
  if (!Communicator::world().mpi_) return;
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (finalized) return;
  // Ranks that finish first (the root still writes the result files) wait here without
  // spinning: MPI_Finalize's own synchronisation would keep a core busy on a shared machine.
  try {
    Communicator::world().barrier();
  } catch (const std::exception&) {
  }
  MPI_Finalize();
}

void DistributedSession::abort(int code) {
  if (Communicator::world().mpi_) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

#else  // one process: the collectives are the identity

void Communicator::barrier() {}

std::vector<std::uint8_t> Communicator::broadcast(std::vector<std::uint8_t> bytes, int) {
  return bytes;
}

void Communicator::send(int, int, std::span<const std::uint8_t>) {
  throw std::logic_error("Communicator::send without MPI");
}

std::vector<std::uint8_t> Communicator::receive(int, int) {
  throw std::logic_error("Communicator::receive without MPI");
}

bool Communicator::try_receive(int, int&, std::vector<std::uint8_t>&) {
  return false;
}

std::vector<std::vector<std::uint8_t>> Communicator::gather(std::span<const std::uint8_t> bytes,
                                                            int) {
  std::vector<std::vector<std::uint8_t>> out;
  out.emplace_back(bytes.begin(), bytes.end());
  return out;
}

bool Communicator::any(bool flag) {
  return flag;
}

DistributedSession::DistributedSession(int&, char**&) {
  const int size = launched_size();
  if (size > 1)
    throw ParameterError(fmt::format(
        "launched as one of {} MPI ranks, but this prtlab was built without MPI: every rank "
        "would run the whole job and overwrite the others' files. Install Open MPI "
        "(libopenmpi-dev) and rebuild (cmake -DPRTLAB_MPI=ON), or run without mpirun",
        size));
}

DistributedSession::~DistributedSession() = default;

void DistributedSession::abort(int code) {
  std::exit(code);
}

#endif

}  // namespace prt
