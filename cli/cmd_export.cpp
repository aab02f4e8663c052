// PLACEHOLDER: replaced by the real 'gtn export' command.
#include "cli/commands.h"

namespace gtn::cli {

Command addExportCommand(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("export", "(not implemented yet)");
  sub->allow_extras();
  return {sub, [] { return reportError(unsupported("'gtn export' is not implemented yet")); }};
}

}  // namespace gtn::cli
