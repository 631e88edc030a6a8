#pragma once
// Cluster refits spread over the ranks of a collective run (prtlab compress under mpirun): the
// refits of one pass are independent, so a work queue hands them out, largest cluster first,
// each rank fits its clusters as one process would (a fit does not depend on the thread count),
// and every rank then receives every fit, bit for bit, so that all ranks continue with the
// model one process has.
#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include "prtlab/distributed/communicator.h"
#include "srbf_cta/clustered_tensor.h"

namespace prt::srbf_cta {

/// What a refit of cluster c changes: its bases and error, its vertex basis U_v and its
/// members' rows of the weights.
struct ClusterFitState {
  CtaCluster* cluster = nullptr;
  Eigen::MatrixXd* vertex_basis = nullptr;
  RowMajorMatrixXd* weights = nullptr;  ///< the model's, vertices x R3
};

/// Runs fit(c) for every c in `which` on some rank (each rank's threads take clusters from one
/// work queue), then gives every rank every fitted cluster's state through `state(c)`.
/// Collective over `comm`.
void fit_clusters_on_ranks(Communicator& comm, std::span<const std::size_t> which,
                           const std::function<std::size_t(std::size_t)>& members,
                           const std::function<void(std::size_t)>& fit,
                           const std::function<ClusterFitState(std::size_t)>& state);

}  // namespace prt::srbf_cta
