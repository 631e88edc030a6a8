#include <fmt/format.h>

#include "commands.h"

namespace prt::cli {

std::optional<std::string> unknown_command(const CLI::App& app) {
  const CLI::App* cur = &app;
  std::string path = cur->get_name();
  for (;;) {
    const CLI::App* next = nullptr;
    for (const CLI::App* sub : cur->get_subcommands())
      if (sub->parsed()) next = sub;
    if (!next) break;
    cur = next;
    path += " " + cur->get_name();
  }
  const auto subs = cur->get_subcommands([](const CLI::App*) { return true; });
  if (subs.empty()) return std::nullopt;
  // With fallthrough the words a subcommand did not take are left with the top-level app.
  std::vector<std::string> rest = cur->remaining();
  if (rest.empty()) rest = app.remaining();
  if (rest.empty() || rest.front().starts_with("-")) return std::nullopt;
  std::string names;
  for (const CLI::App* sub : subs) names += (names.empty() ? "" : ", ") + sub->get_name();
  return fmt::format("unknown command '{}' for '{}' (commands: {})", rest.front(), path, names);
}

}  // namespace prt::cli
