#include "cli/level_view.h"

#include "convert/import.h"

namespace gtn::cli {

StatusOr<std::unique_ptr<GtnReader>> openForView(const std::string& input, const std::string& command,
                                                 const std::string& convert_hint, HeldWarnings& damage) {
  GtnOpenOptions oo;
  oo.verify = false;  // random access through the directory; every chunk read is still checksummed
  auto reader = openGtnChecked(input, oo, damage.sink());
  if (reader.isOk()) return reader;
  const InputFormat in_format = detectInputFormat(input);
  if (in_format != InputFormat::kGtn && in_format != InputFormat::kUnknown)
    return usageError(input + ": a " + inputFormatName(in_format) + " file, not .gtn: 'gtn " + command +
                      "' reads .gtn files; " + convert_hint);
  return reader.status();
}

Status decodeView(GtnReader& r, const std::string& input, const ViewRequest& v, MeshSink& sink, DecodeFields* fields,
                  SimplifyPlan* plan) {
  if (v.level >= r.levels())
    return usageError(input + ": --level " + std::to_string(v.level) + ": the file holds " +
                      std::to_string(r.levels()) + " level(s), 0 to " + std::to_string(r.levels() - 1));
  *fields = DecodeFields{};  // every field unless v.fields names some
  if (!v.fields.empty()) {
    auto selected = selectDecodeFields(r.level(v.level).header, v.fields, input, "--fields");
    if (!selected.isOk()) return selected.status();
    *fields = std::move(selected).value();
  }
  if (plan) plan->level = v.level;
  if (v.ratio < 0 && v.merges < 0) return r.decodeLevel(v.level, sink, nullptr, fields);
  StatusOr<uint64_t> target = uint64_t{0};
  if (v.merges >= 0) target = static_cast<uint64_t>(v.merges);
  else target = mergesForRatio(r, v.ratio);
  if (!target.isOk()) return target.status();
  return streamSimplified(r, *target, sink, plan, /*clamp=*/v.merges < 0, fields);
}

}  // namespace gtn::cli
