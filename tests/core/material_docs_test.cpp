// A material backend's README that documents its parameters in a table ("| key | type |
// default | ...") lists every parameter the registry declares (the shared ones included) with
// the registry's default, and no key the registry lacks: material READMEs are not generated
// (scripts/gen_backend_docs.py covers transfer backends), so this keeps them honest.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "prtlab/compress/material_registry.h"
#include "prtlab/compress/params.h"

namespace prt {
namespace {

TEST(MaterialDocs, ParameterTablesMatchTheRegistry) {
  int checked = 0;
  for (const std::string& name : MaterialRegistry::instance().names()) {
    const std::filesystem::path readme =
        std::filesystem::path(PRTLAB_SOURCE_DIR) / "compressors" / name / "README.md";
    std::ifstream in(readme);
    if (!in) continue;
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    if (text.find("| key | type | default |") == std::string::npos) continue;
    SCOPED_TRACE(readme.string());
    std::map<std::string, std::string> documented;
    const std::regex row(R"(\| `([a-z_0-9]+)` \| [a-z]+ \| `([^`]*)` \|)");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), row);
         it != std::sregex_iterator(); ++it)
      documented[(*it)[1]] = (*it)[2];
    std::set<std::string> declared;
    const auto check = [&](const ParamSpec& s) {
      declared.insert(s.key);
      ASSERT_TRUE(documented.contains(s.key)) << "parameter " << s.key << " is not in the table";
      EXPECT_EQ(documented.at(s.key), s.default_value) << "default of " << s.key;
    };
    for (const ParamSpec& s : MaterialRegistry::instance().get(name).params) check(s);
    for (const ParamSpec& s : shared_param_specs()) check(s);
    for (const auto& [key, unused] : documented)
      EXPECT_TRUE(declared.contains(key))
          << "the table documents " << key << ", which is not a parameter";
    ++checked;
  }
  EXPECT_GE(checked, 2) << "cmf and hf document their parameters in tables";
}

}  // namespace
}  // namespace prt
