// PLACEHOLDER: replaced by the real 'gtn render' command.
#include "cli/commands.h"

namespace gtn::cli {

Command addRenderCommand(CLI::App& app) {
  CLI::App* sub = app.add_subcommand("render", "(not implemented yet)");
  sub->allow_extras();
  return {sub, [] { return reportError(unsupported("'gtn render' is not implemented yet")); }};
}

}  // namespace gtn::cli
