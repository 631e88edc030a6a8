#pragma once
// Rendering a computed paper table (paper_table.h) as markdown, CSV and JSON, and writing the
// three files atomically: <out>/<table>.md, <out>/<table>.csv, <out>/<table>.json.
//
// CSV: one header line, one line per scene; numbers in shortest round-trip form, "n/a" where a
// value does not exist (no OpenCL device, a scene the paper does not list), never 0 or blank.
// Columns: see csv_columns() (docs/experiments.md lists them with units). The provenance is in
// leading "# key: value" comment lines, so `pandas.read_csv(comment='#')` reads the table.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "paper_table.h"

namespace prt::experiments {

/// The CSV header, in order.
std::vector<std::string> csv_columns();

/// Explanations of where our numbers differ from the paper's, with the measured quantities.
std::vector<std::string> table_notes(const TableResult& result);

std::string render_markdown(const TableResult& result);
std::string render_csv(const TableResult& result);
nlohmann::json to_json(const TableResult& result);

/// Writes the three files (each atomically; the directory is created) and returns their paths
/// (md, csv, json).
std::vector<std::filesystem::path> write_table_files(const TableResult& result,
                                                     const std::filesystem::path& out_dir);

}  // namespace prt::experiments
