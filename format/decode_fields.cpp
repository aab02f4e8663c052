#include "format/decode_fields.h"

namespace gtn {

StatusOr<DecodeFields> selectDecodeFields(const LevelHeader& h, const std::vector<std::string>& names,
                                          const std::string& input, const std::string& option) {
  DecodeFields d;
  d.point.assign(h.point_fields.size(), false);
  d.cell.assign(h.cell_fields.size(), false);
  for (const std::string& name : names) {
    bool found = false;
    for (size_t f = 0; f < h.point_fields.size(); ++f)
      if (h.point_fields[f].name == name) d.point[f] = found = true;
    for (size_t f = 0; f < h.cell_fields.size(); ++f)
      if (h.cell_fields[f].name == name) d.cell[f] = found = true;
    if (found) continue;
    std::string known;
    for (const auto* list : {&h.point_fields, &h.cell_fields})
      for (const FieldDesc& f : *list) known += (known.empty() ? "" : ", ") + f.name;
    return usageError(input + ": " + option + ": no field named '" + name + "' (" +
                      (known.empty() ? std::string("the file has no fields") : "fields: " + known) + ")");
  }
  return d;
}

void dropUndecodedFields(TetMesh& mesh, const DecodeFields& keep) {
  auto drop = [](std::vector<Field>& fields, const std::vector<bool>& kept) {
    std::vector<Field> out;
    for (size_t f = 0; f < fields.size(); ++f)
      if (f < kept.size() && kept[f]) out.push_back(std::move(fields[f]));
    fields = std::move(out);
  };
  drop(mesh.point_fields, keep.point);
  drop(mesh.cell_fields, keep.cell);
}

}  // namespace gtn
