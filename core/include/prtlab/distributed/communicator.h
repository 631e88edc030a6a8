#pragma once
// The group of processes a run is spread over: MPI's world when prtlab is built with MPI and
// launched by mpirun or srun, one process otherwise (docs/distributed.md). Everything that
// distributes work goes through this class, so a build or a launch without MPI runs exactly the
// single-process code.
#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace prt {

class Communicator {
 public:
  /// This process's group. Before a DistributedSession (or without MPI): one process.
  static Communicator& world();

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool is_root() const { return rank_ == 0; }
  bool distributed() const { return size_ > 1; }

  void barrier();
  /// The root's bytes on every rank.
  std::vector<std::uint8_t> broadcast(std::vector<std::uint8_t> bytes, int root = 0);
  /// Every rank's bytes at the root, in rank order; an empty list on the other ranks.
  std::vector<std::vector<std::uint8_t>> gather(std::span<const std::uint8_t> bytes, int root = 0);
  /// A logical OR of every rank's flag, on every rank.
  bool any(bool flag);

  /// Point-to-point messages (used by WorkQueue); tags below kUserTagLimit.
  void send(int to, int tag, std::span<const std::uint8_t> bytes);
  std::vector<std::uint8_t> receive(int from, int tag);
  /// A message from any rank with this tag, if one has arrived (never blocks); `from` receives
  /// its sender.
  bool try_receive(int tag, int& from, std::vector<std::uint8_t>& bytes);
  /// A tag no earlier call returned on this rank: collective, so every rank gets the same one.
  int fresh_tag();

  /// Bytes this rank sent, in every call above (the communication volume of a stage).
  std::uint64_t bytes_sent() const { return bytes_sent_.load(); }
  /// "1 process" or "N MPI ranks (Open MPI x.y)".
  std::string description() const;

  Communicator(const Communicator&) = delete;
  Communicator& operator=(const Communicator&) = delete;

 private:
  friend class DistributedSession;
  Communicator() = default;
  int rank_ = 0, size_ = 1;
  bool mpi_ = false;
  int next_tag_ = 100;
  std::atomic<std::uint64_t> bytes_sent_{0};  // the work queue's server thread sends too
};

/// MPI's lifetime, held by main(): initialises MPI when the build has it and the process was
/// launched by an MPI starter (mpirun, mpiexec, srun), leaves it alone otherwise, and finalises
/// it at the end of the scope.
class DistributedSession {
 public:
  DistributedSession(int& argc, char**& argv);
  ~DistributedSession();
  DistributedSession(const DistributedSession&) = delete;
  DistributedSession& operator=(const DistributedSession&) = delete;
  /// Ends every rank at once after an error on one (the others would wait for it forever).
  [[noreturn]] static void abort(int code);
};

/// Marks what runs inside it as collective over `comm`: every rank runs the same computation
/// (`prtlab compress` on several ranks), so a backend may split its own work over the ranks
/// (bicluster's row groups). Outside a scope, as in an experiment's point that one rank measures
/// alone, collective() is null and every backend computes alone.
class CollectiveScope {
 public:
  explicit CollectiveScope(Communicator& comm);
  ~CollectiveScope();
  CollectiveScope(const CollectiveScope&) = delete;
  CollectiveScope& operator=(const CollectiveScope&) = delete;

 private:
  Communicator* previous_;
};

/// The communicator of the innermost CollectiveScope, or null.
Communicator* collective();

/// Whether this build can run on several processes (prtlab built with MPI).
bool mpi_available();
/// Whether the environment says an MPI starter launched this process.
bool launched_by_mpi();

}  // namespace prt
