#include "paper_numbers.h"

#include <array>

#include "prtlab/base/error.h"

namespace prt::experiments {
namespace {

// Transcribed from the paper's tables (the text in ../shared/papers); DESIGN.md repeats them.
const std::array<PaperRow, 4> kTable1 = {{
    {"bunny", 3286, 10.6, 21.2, 5.8, 27.4, 1400, 24.2, 1.7, 12, "97.0/56.1"},
    {"armor", 10652, 21.9, 43.9, 14.9, 33.9, 9500, 59.0, 0.62, 46, "42.8/24.9"},
    {"chair", 16101, 40.5, 81.0, 9.0, 11.1, 6300, 36.4, 0.58, 33, "51.8/33.7"},
    {"temple", 32409, 62.8, 125.6, 7.9, 6.3, 12600, 32.9, 0.26, 59, "61.1/34.3"},
}};
const std::array<PaperRow, 3> kTable2 = {{
    {"bunny", 3286, 10.6, 21.2, 5.8, 27.4, 1400, 24.2, 1.7, 12, "277.9/86.8"},
    {"bunny-12k", 12380, 39.2, 78.4, 21.2, 27.0, 4868, 84.1, 1.7, 49, "115.8/32.3"},
    {"bunny-48k", 47960, 151.3, 302.7, 80.7, 26.7, 18859, 316.9, 1.7, 279, "48.5/11.9"},
}};

template <std::size_t K>
std::optional<PaperRow> find(const std::array<PaperRow, K>& rows, std::string_view scene) {
  for (const auto& r : rows)
    if (r.scene == scene) return r;
  return std::nullopt;
}

}  // namespace

std::string_view to_string(PaperTable table) {
  return table == PaperTable::kTable1 ? "table1" : "table2";
}

PaperTable parse_paper_table(std::string_view name) {
  if (name == "table1") return PaperTable::kTable1;
  if (name == "table2") return PaperTable::kTable2;
  throw ParameterError(fmt::format("unknown paper table '{}' (known: table1, table2)", name));
}

std::string_view caption(PaperTable table) {
  return table == PaperTable::kTable1 ? "Table I: test scene statistics"
                                      : "Table II: scalability test results";
}

std::string_view short_name(PaperTable table) {
  return table == PaperTable::kTable1 ? "Table I" : "Table II";
}

std::vector<std::string> table_scenes(PaperTable table) {
  std::vector<std::string> out;
  if (table == PaperTable::kTable1)
    for (const auto& r : kTable1) out.push_back(r.scene);
  else
    for (const auto& r : kTable2) out.push_back(r.scene);
  return out;
}

std::optional<PaperRow> paper_row(PaperTable table, std::string_view scene) {
  return table == PaperTable::kTable1 ? find(kTable1, scene) : find(kTable2, scene);
}

}  // namespace prt::experiments
