// PLACEHOLDER: replaced by the real 'gtn compare' command.
#include "cli/commands.h"

namespace gtn::cli {

Command addCompareCommand(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("compare", "(not implemented yet)");
  sub->allow_extras();
  return {sub, [] { return reportError(unsupported("'gtn compare' is not implemented yet")); }};
}

}  // namespace gtn::cli
