#include "prtlab/transfer/transfer_io.h"

#include "prtlab/base/error.h"

namespace prt {

ArchiveWriter save_transfer(const TransferResult& result) {
  const TransferMatrix& t = result.transfer;
  ArchiveWriter w(std::string(kTransferArchiveKind), kTransferArchiveVersion);
  w.add_meta("vertices", t.vertex_count());
  w.add_meta("local_count", t.local_count());
  w.add_meta("pixel_count", t.cols());
  w.add_meta("supersampling", t.supersampling());
  w.add_meta("sh_order", result.sh ? result.sh->order() : 0);
  const TransferStats& s = result.stats;
  w.add_meta("stats", nlohmann::json{{"points", s.points},
                                     {"threads", s.threads},
                                     {"ranks", s.ranks},
                                     {"subrays", s.subrays},
                                     {"rays_traced", s.rays_traced},
                                     {"rays_unblocked", s.rays_unblocked},
                                     {"horizon_lifted", s.horizon_lifted},
                                     {"seconds_total", s.seconds_total},
                                     {"seconds_setup", s.seconds_setup},
                                     {"seconds_points", s.seconds_points},
                                     {"seconds_assemble", s.seconds_assemble},
                                     {"thread_seconds_trace", s.thread_seconds_trace},
                                     {"thread_seconds_bin", s.thread_seconds_bin},
                                     {"thread_seconds_sh", s.thread_seconds_sh}});
  w.add_section("row_offsets", t.row_offsets());
  if (t.narrow_columns())
    w.add_section("columns", t.columns16());
  else
    w.add_section("columns", t.columns32());
  w.add_section("counts", t.counts());
  if (result.sh) w.add_section("sh", result.sh->data());
  return w;
}

TransferResult load_transfer(const ArchiveReader& r) {
  r.expect_kind(kTransferArchiveKind, kTransferArchiveVersion);
  const auto vertices = r.meta_value<std::size_t>("vertices");
  const auto m = r.meta_value<int>("local_count");
  const auto n = r.meta_value<int>("pixel_count");
  const auto s = r.meta_value<int>("supersampling");
  const auto sh_order = r.meta_value<int>("sh_order");
  TransferResult out;
  const std::vector<std::uint32_t> columns = r.indices("columns");
  try {
    out.transfer =
        TransferMatrix::from_csr(vertices, m, n, s, r.section<std::uint32_t>("row_offsets"),
                                 columns, r.section<std::uint8_t>("counts"));
  } catch (const ParameterError& e) {
    throw InputError(r.path(), fmt::format("invalid transfer matrix: {}", e.what()));
  }
  if (sh_order > 0) {
    ShTransfer sh(sh_order, vertices);
    const auto data =
        r.view<double>("sh", static_cast<std::uint64_t>(vertices) * sh.dim() * sh.dim());
    std::copy(data.begin(), data.end(), sh.mutable_data().begin());
    out.sh = std::move(sh);
  }
  if (r.meta().contains("stats")) {
    const auto& j = r.meta()["stats"];
    TransferStats& st = out.stats;
    st.points = j.value("points", std::size_t{0});
    st.threads = j.value("threads", 0);
    st.ranks = j.value("ranks", 1);
    st.subrays = j.value("subrays", std::uint64_t{0});
    st.rays_traced = j.value("rays_traced", std::uint64_t{0});
    st.rays_unblocked = j.value("rays_unblocked", std::uint64_t{0});
    st.horizon_lifted = j.value("horizon_lifted", std::uint64_t{0});
    st.seconds_total = j.value("seconds_total", 0.0);
    st.seconds_setup = j.value("seconds_setup", 0.0);
    st.seconds_points = j.value("seconds_points", 0.0);
    st.seconds_assemble = j.value("seconds_assemble", 0.0);
    st.thread_seconds_trace = j.value("thread_seconds_trace", 0.0);
    st.thread_seconds_bin = j.value("thread_seconds_bin", 0.0);
    st.thread_seconds_sh = j.value("thread_seconds_sh", 0.0);
  }
  return out;
}

}  // namespace prt
