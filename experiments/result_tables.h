#pragma once
// The machine-readable files of a result folder: result.json and the two fixed-schema CSVs
// (points.csv: experiment, variant, then point_record_columns(); errors.csv: experiment,
// variant, then error_record_columns()). Written atomically; equal results give equal bytes.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace prt::experiments {

/// Writes result.json, points.csv and errors.csv into `folder`.
void write_result_files(const nlohmann::json& result, const std::filesystem::path& folder);

/// The header of points.csv / errors.csv.
std::vector<std::string> points_csv_header();
std::vector<std::string> errors_csv_header();

/// One CSV cell: null is empty, strings are quoted when they hold a comma, quote or newline.
std::string csv_cell(const nlohmann::json& value);

}  // namespace prt::experiments
