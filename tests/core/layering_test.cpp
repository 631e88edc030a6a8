// The layering of docs/architecture.md holds: every #include "..." under core/ stays inside the
// folders its subsystem's row allows, every core folder has a row, the table has no cycle, and
// a backend folder includes only core headers and its own files. A planted back edge in a copy
// of the layout is caught (so the check itself can fail).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/temp_dir.h"

namespace prt {
namespace {
namespace fs = std::filesystem;

using Rules = std::map<std::string, std::set<std::string>>;

std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t`");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t`");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(s);
  while (std::getline(in, part, sep)) parts.push_back(trim(part));
  return parts;
}

/// The rows between <!-- layering:begin --> and <!-- layering:end -->: "| folder | a, b |".
Rules read_rules(const fs::path& doc) {
  std::ifstream in(doc);
  if (!in) throw std::runtime_error("cannot read " + doc.string());
  Rules rules;
  bool inside = false;
  for (std::string line; std::getline(in, line);) {
    if (line.find("<!-- layering:begin -->") != std::string::npos) {
      inside = true;
      continue;
    }
    if (line.find("<!-- layering:end -->") != std::string::npos) break;
    if (!inside || line.empty() || line[0] != '|') continue;
    const auto cells = split(line.substr(1), '|');
    if (cells.empty() || cells[0].empty() || cells[0] == "folder" ||
        cells[0].find("---") != std::string::npos)
      continue;
    auto& allowed = rules[cells[0]];
    if (cells.size() > 1)
      for (const auto& dep : split(cells[1], ','))
        if (!dep.empty()) allowed.insert(dep);
  }
  return rules;
}

/// Every quoted include of a file: `#include "x/y.h"` -> "x/y.h".
std::vector<std::string> quoted_includes(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> includes;
  for (std::string line; std::getline(in, line);) {
    const auto t = trim(line);
    if (t.rfind("#include \"", 0) != 0) continue;
    const auto end = t.find('"', 10);
    if (end != std::string::npos) includes.push_back(t.substr(10, end - 10));
  }
  return includes;
}

bool is_source(const fs::path& p) {
  const auto e = p.extension();
  return e == ".h" || e == ".cpp" || e == ".hpp" || e == ".cl";
}

/// The folder a core include names: "prtlab/sphere/cubemap.h" and (private) "sphere/x.h" both
/// give "sphere"; a bare "x.h" is the including file's own folder.
std::string included_folder(const std::string& include, const std::string& own) {
  std::string rest = include;
  if (rest.rfind("prtlab/", 0) == 0) rest = rest.substr(7);
  const auto slash = rest.find('/');
  return slash == std::string::npos ? own : rest.substr(0, slash);
}

/// Violations of the core rules, one line each ("file: includes x (folder f), not allowed").
std::vector<std::string> check_core(const fs::path& root, const Rules& rules) {
  std::vector<std::string> violations;
  for (const fs::path& base : {root / "core/include/prtlab", root / "core/src"}) {
    if (!fs::exists(base)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(base)) {
      if (!entry.is_regular_file() || !is_source(entry.path())) continue;
      const auto rel = fs::relative(entry.path(), base);
      if (rel.begin() == rel.end() || std::next(rel.begin()) == rel.end()) {
        violations.push_back(entry.path().string() + ": not inside a subsystem folder");
        continue;
      }
      const std::string own = rel.begin()->string();
      if (!rules.contains(own)) {
        violations.push_back(entry.path().string() + ": folder '" + own +
                             "' has no row in docs/architecture.md");
        continue;
      }
      for (const auto& inc : quoted_includes(entry.path())) {
        const auto folder = included_folder(inc, own);
        if (folder == own || rules.at(own).contains(folder)) continue;
        violations.push_back(entry.path().string() + ": includes \"" + inc + "\" (folder '" +
                             folder + "'), which '" + own + "' may not use");
      }
    }
  }
  return violations;
}

/// A backend folder may include core ("prtlab/...") and its own files, nothing else.
std::vector<std::string> check_backends(const fs::path& root) {
  std::vector<std::string> violations;
  const auto dir = root / "compressors";
  if (!fs::exists(dir)) return violations;
  for (const auto& backend : fs::directory_iterator(dir)) {
    if (!backend.is_directory()) continue;
    const std::string name = backend.path().filename().string();
    for (const auto& entry : fs::recursive_directory_iterator(backend.path())) {
      if (!entry.is_regular_file() || !is_source(entry.path())) continue;
      for (const auto& inc : quoted_includes(entry.path())) {
        if (inc.rfind("prtlab/", 0) == 0) continue;
        if (inc.rfind("support/", 0) == 0 && fs::exists(root / "tests" / inc)) continue;
        if (inc.rfind(name + "/", 0) == 0 && fs::exists(dir / inc)) continue;
        if (fs::exists(entry.path().parent_path() / inc)) continue;
        violations.push_back(entry.path().string() + ": includes \"" + inc +
                             "\", which is neither core nor backend '" + name + "'");
      }
    }
  }
  return violations;
}

/// A folder that reaches itself through the table (a cycle), or "" when there is none.
std::string find_cycle(const Rules& rules) {
  std::map<std::string, int> state;  // 0 unseen, 1 on the stack, 2 done
  std::string cycle;
  std::function<bool(const std::string&)> visit = [&](const std::string& f) {
    if (state[f] == 1) {
      cycle = f;
      return true;
    }
    if (state[f] == 2) return false;
    state[f] = 1;
    if (rules.contains(f))
      for (const auto& d : rules.at(f))
        if (visit(d)) return true;
    state[f] = 2;
    return false;
  };
  for (const auto& [f, deps] : rules)
    if (visit(f)) return cycle;
  return {};
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += "  " + l + "\n";
  return s;
}

const fs::path kSource = PRTLAB_SOURCE_DIR;

TEST(Layering, TheTableNamesEveryCoreFolderAndHasNoCycle) {
  const auto rules = read_rules(kSource / "docs/architecture.md");
  ASSERT_GE(rules.size(), 8u) << "docs/architecture.md lost its layering table";
  EXPECT_EQ(find_cycle(rules), "");
  for (const auto& [folder, deps] : rules)
    for (const auto& d : deps) EXPECT_TRUE(rules.contains(d)) << folder << " names unknown " << d;
  for (const auto& entry : fs::directory_iterator(kSource / "core/include/prtlab")) {
    if (entry.is_directory()) {
      EXPECT_TRUE(rules.contains(entry.path().filename().string()))
          << entry.path() << " has no row in docs/architecture.md";
    }
  }
}

TEST(Layering, CoreIncludesFollowTheTable) {
  const auto violations = check_core(kSource, read_rules(kSource / "docs/architecture.md"));
  EXPECT_TRUE(violations.empty()) << joined(violations);
}

TEST(Layering, BackendsIncludeOnlyCoreAndTheirOwnFiles) {
  const auto violations = check_backends(kSource);
  EXPECT_TRUE(violations.empty()) << joined(violations);
}

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

TEST(Layering, APlantedBackEdgeFails) {
  testing::TempDir tmp("layering");
  const auto root = tmp.path();
  const auto rules = read_rules(kSource / "docs/architecture.md");
  write(root / "core/include/prtlab/sphere/cubemap.h", "#include \"prtlab/base/types.h\"\n");
  write(root / "core/src/sphere/cubemap.cpp", "#include \"prtlab/sphere/cubemap.h\"\n");
  EXPECT_TRUE(check_core(root, rules).empty()) << joined(check_core(root, rules));

  // sphere -> render is a back edge: render sits above sphere.
  write(root / "core/src/sphere/cubemap.cpp",
        "#include \"prtlab/sphere/cubemap.h\"\n#include \"prtlab/render/gbuffer.h\"\n");
  const auto violations = check_core(root, rules);
  ASSERT_EQ(violations.size(), 1u) << joined(violations);
  EXPECT_NE(violations[0].find("cubemap.cpp"), std::string::npos) << violations[0];
  EXPECT_NE(violations[0].find("'render'"), std::string::npos) << violations[0];

  // A private header of another subsystem is the same back edge.
  write(root / "core/src/base/log.cpp", "#include \"geometry/embree_triangle_scene.h\"\n");
  EXPECT_EQ(check_core(root, rules).size(), 2u);

  // A folder the table does not name.
  write(root / "core/include/prtlab/misc/grab_bag.h", "\n");
  EXPECT_EQ(check_core(root, rules).size(), 3u);
}

TEST(Layering, ABackendIncludingAnotherBackendFails) {
  testing::TempDir tmp("layering_backend");
  const auto root = tmp.path();
  write(root / "compressors/alpha/alpha.h", "#include \"prtlab/compress/compressor.h\"\n");
  write(root / "compressors/alpha/alpha.cpp", "#include \"alpha.h\"\n");
  write(root / "compressors/beta/beta.cpp",
        "#include \"beta.h\"\n#include \"alpha/alpha.h\"\n#include \"paper_table.h\"\n");
  write(root / "compressors/beta/beta.h", "\n");
  const auto violations = check_backends(root);
  ASSERT_EQ(violations.size(), 2u) << joined(violations);
  EXPECT_NE(violations[0].find("alpha/alpha.h"), std::string::npos) << violations[0];
  EXPECT_NE(violations[1].find("paper_table.h"), std::string::npos) << violations[1];
}

TEST(Layering, ACycleInTheTableIsFound) {
  Rules rules = {{"a", {"b"}}, {"b", {"c"}}, {"c", {"a"}}};
  EXPECT_NE(find_cycle(rules), "");
  rules["c"].clear();
  EXPECT_EQ(find_cycle(rules), "");
}

}  // namespace
}  // namespace prt
