// PLACEHOLDER: replaced by the real 'gtn validate' command.
#include "cli/commands.h"

namespace gtn::cli {

Command addValidateCommand(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("validate", "(not implemented yet)");
  sub->allow_extras();
  return {sub, [] { return reportError(unsupported("'gtn validate' is not implemented yet")); }};
}

}  // namespace gtn::cli
