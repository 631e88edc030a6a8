#pragma once
// The numbers the central paper publishes in its Table I and Table II (Sun et al.,
// "Biclustering for all-frequency bi-scale PRT"; ../shared/papers and DESIGN.md), and the scenes
// each table lists. Our scene files stand in for the paper's scenes (docs/scenes.md).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace prt::experiments {

enum class PaperTable {
  kTable1,  ///< "Test scene statistics": bunny, armor, chair, temple
  kTable2,  ///< "Scalability test results": the bunny at 3,286 / 12,380 / 47,960 vertices
};

/// "table1" / "table2" (also the stem of the result files).
std::string_view to_string(PaperTable table);
/// Inverse of to_string; throws ParameterError naming the valid tables.
PaperTable parse_paper_table(std::string_view name);
/// The paper's caption ("Table I: test scene statistics").
std::string_view caption(PaperTable table);
/// "Table I" / "Table II".
std::string_view short_name(PaperTable table);

/// One column of the paper's table (its units: millions, MB = 1e6 bytes, minutes).
struct PaperRow {
  std::string scene;  ///< our scene file's name (scenes/<scene>.toml)
  double vertices = 0;
  double nnz_millions = 0;
  double mflops = 0;          ///< 2 nnz(T), per colour channel
  double reduced_mflops = 0;  ///< after biclustering
  double computation_percent = 0;
  double data_mb = 0;  ///< dense T at one byte per entry
  double reduced_mb = 0;
  double data_percent = 0;
  double precompute_minutes = 0;  ///< transfer + biclustering, 2008 quad Xeon
  std::string fps;                ///< "view / light" average frame rates (not regenerated yet)
};

/// The scenes of the table, in the paper's order.
std::vector<std::string> table_scenes(PaperTable table);
/// The paper's numbers for `scene` in `table`; nullopt for scenes the table does not list.
std::optional<PaperRow> paper_row(PaperTable table, std::string_view scene);

}  // namespace prt::experiments
