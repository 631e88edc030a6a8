#include "result_tables.h"

#include <fmt/format.h>

#include <algorithm>

#include "point_measurement.h"
#include "prtlab/storage/atomic_file.h"

namespace prt::experiments {
namespace {
using json = nlohmann::json;

std::string csv_line(const std::vector<std::string>& cells) {
  std::string s;
  for (std::size_t i = 0; i < cells.size(); ++i) s += (i ? "," : "") + cells[i];
  return s + "\n";
}

}  // namespace

std::string csv_cell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number_float()) return fmt::format("{}", v.get<double>());
  const std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  // '#' too: readers skipping comment lines (pandas comment='#') cut a line there.
  if (s.find_first_of(",\"\n\r#") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::vector<std::string> points_csv_header() {
  std::vector<std::string> h = {"experiment", "variant"};
  for (const auto& c : point_record_columns()) h.push_back(c);
  return h;
}

std::vector<std::string> errors_csv_header() {
  std::vector<std::string> h = {"experiment", "variant"};
  for (const auto& c : error_record_columns()) h.push_back(c);
  return h;
}

void write_result_files(const json& result, const std::filesystem::path& folder) {
  const json& spec = result.at("experiment");
  const json experiment = spec.at("name"), variant = spec.at("variant");
  // Provenance first, as comment lines (pandas.read_csv(comment='#') skips them).
  const json& prov = result.at("provenance");
  std::string command = prov.value("command", std::string());
  std::replace(command.begin(), command.end(), '\n', ' ');
  std::replace(command.begin(), command.end(), '\r', ' ');
  std::string head =
      fmt::format("# experiment: {} {}\n# command: {}\n# provenance: {}\n",
                  experiment.get<std::string>(), variant.get<std::string>(), command, prov.dump());
  std::string points = head + csv_line(points_csv_header());
  std::string errors = head + csv_line(errors_csv_header());
  for (const auto& p : result.at("points")) {
    std::vector<std::string> row = {csv_cell(experiment), csv_cell(variant)};
    for (const auto& c : point_record_columns()) row.push_back(csv_cell(p.value(c, json(nullptr))));
    points += csv_line(row);
    for (const auto& e : p.at("errors")) {
      std::vector<std::string> er = {csv_cell(experiment), csv_cell(variant)};
      for (const auto& c : error_record_columns())
        er.push_back(csv_cell(e.contains(c) ? e.at(c) : p.value(c, json(nullptr))));
      errors += csv_line(er);
    }
  }
  write_text_atomically(folder / "points.csv", points);
  write_text_atomically(folder / "errors.csv", errors);
  write_text_atomically(folder / "result.json", result.dump(2) + "\n");
}

}  // namespace prt::experiments
