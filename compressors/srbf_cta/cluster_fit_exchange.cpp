#include "srbf_cta/cluster_fit_exchange.h"

#include <algorithm>
#include <numeric>

#include "prtlab/base/error.h"
#include "prtlab/base/log.h"
#include "prtlab/distributed/byte_stream.h"
#include "prtlab/distributed/shared_work.h"

namespace prt::srbf_cta {
namespace {

template <class M>
void put_matrix(ByteWriter& w, const M& m) {
  w.put<std::int64_t>(m.rows());
  w.put<std::int64_t>(m.cols());
  w.put_array(std::span<const double>(m.data(), static_cast<std::size_t>(m.size())));
}

template <class M>
M get_matrix(ByteReader& r) {
  const auto rows = r.get<std::int64_t>(), cols = r.get<std::int64_t>();
  const std::vector<double> values = r.get_array<double>();
  PRT_CHECK(rows >= 0 && cols >= 0 && static_cast<std::size_t>(rows * cols) == values.size(),
            "srbf_cta: a {} x {} matrix of {} values from another rank", rows, cols, values.size());
  return Eigen::Map<const M>(values.data(), rows, cols);
}

void put_state(ByteWriter& w, std::size_t c, const ClusterFitState& s) {
  w.put<std::uint64_t>(c);
  put_matrix(w, s.cluster->light);
  put_matrix(w, s.cluster->dual);
  w.put<double>(s.cluster->squared_error);
  put_matrix(w, *s.vertex_basis);
  RowMajorMatrixXd rows(static_cast<Eigen::Index>(s.cluster->members.size()), s.weights->cols());
  for (std::size_t k = 0; k < s.cluster->members.size(); ++k)
    rows.row(static_cast<Eigen::Index>(k)) = s.weights->row(s.cluster->members[k]);
  put_matrix(w, rows);
}

void get_state(ByteReader& r, const ClusterFitState& s) {
  s.cluster->light = get_matrix<Eigen::MatrixXd>(r);
  s.cluster->dual = get_matrix<RowMajorMatrixXd>(r);
  s.cluster->squared_error = r.get<double>();
  *s.vertex_basis = get_matrix<Eigen::MatrixXd>(r);
  const auto rows = get_matrix<RowMajorMatrixXd>(r);
  PRT_CHECK(static_cast<std::size_t>(rows.rows()) == s.cluster->members.size() &&
                rows.cols() == s.weights->cols(),
            "srbf_cta: another rank's weights are {} x {} for a cluster of {} members", rows.rows(),
            rows.cols(), s.cluster->members.size());
  for (std::size_t k = 0; k < s.cluster->members.size(); ++k)
    s.weights->row(s.cluster->members[k]) = rows.row(static_cast<Eigen::Index>(k));
}

}  // namespace

void fit_clusters_on_ranks(Communicator& comm, std::span<const std::size_t> which,
                           const std::function<std::size_t(std::size_t)>& members,
                           const std::function<void(std::size_t)>& fit,
                           const std::function<ClusterFitState(std::size_t)>& state) {
  if (which.empty()) return;  // on every rank: they all refit the same clusters
  // Largest first, so that the last cluster a rank takes is a small one.
  std::vector<std::size_t> order(which.begin(), which.end());
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return members(a) > members(b); });
  const std::vector<std::uint8_t> all =
      compute_on_all_ranks(comm, order.size(), [&](std::size_t i, std::vector<std::uint8_t>& out) {
        const std::size_t c = order[i];
        fit(c);
        ByteWriter w(out);
        put_state(w, c, state(c));
      });
  std::vector<char> seen(*std::max_element(order.begin(), order.end()) + 1, 0);
  ByteReader r(all, "srbf_cta cluster fits");
  std::size_t received = 0;
  while (!r.done()) {
    const auto c = r.get<std::uint64_t>();
    PRT_CHECK(
        c < seen.size() && !seen[c] && std::find(order.begin(), order.end(), c) != order.end(),
        "srbf_cta: cluster {} came twice or was not refit", c);
    seen[c] = 1;
    get_state(r, state(c));
    ++received;
  }
  PRT_CHECK(received == order.size(), "srbf_cta: {} of {} cluster fits arrived", received,
            order.size());
  log_debug("srbf_cta: {} cluster refits over {} ranks ({} bytes exchanged)", order.size(),
            comm.size(), all.size());
}

}  // namespace prt::srbf_cta
