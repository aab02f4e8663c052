// The form of a value-coded component (spec section 10.2): how a coordinate axis, a point-field
// component or a cell-field component is coded, declared at the start of its stream. A component is
// in table form (its distinct values once, then places in that table), else a float one in decimal
// form (integers times 10^-e) or, for float64, in printed-single form (float32 values printed with p
// digits), else plain with an optional shift (low zero bits dropped, with or without exceptions).
// chooseValueForm is the encoder's choice from the source's values; codeValueForm writes the form
// (encoder) or reads it back and checks it (decoder), and sets it on the component's ValueCoder.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "codec/range_coder.h"
#include "codec/value_coder.h"

namespace gtn::level {

struct ValueForm {
  int decimals = -1;                 // decimal form with this many places (0 to 22), -1 if not
  int printed = 0;                   // printed-single form with this many digits (1 to 17), 0 if not
  uint32_t shift = 0;                // plain form: the low bits dropped
  bool exceptions = false;           // of the shift: some values keep their low bits
  std::vector<uint64_t> table = {};  // table form: the distinct keys, ascending (empty: not)
};

// The encoder's form for `n` values of `type` `stride` bytes apart from `p`: the shift every value
// allows, or whichever of decimal places, printed digits, a larger shift with exceptions or a value
// table is estimated to cost least, when that saves a twentieth. Costs are estimated on the
// differences of consecutive values in the source's order (neighbours there are mostly neighbours in
// space), as bit lengths; over every value, or a pseudo-random sample of 256 pairs for more than 1024.
ValueForm chooseValueForm(ScalarType type, const uint8_t* p, size_t n, size_t stride);

// The models of the form declarations, one set per level shared by all streams.
struct ValueFormModels {
  BitModel table;       // a component is in table form
  BitModel decimal;     // a float component is in decimal form
  BitModel printed;     // a float64 component is in printed-single form
  BitModel shift;       // a component declares a shift
  BitModel exceptions;  // the shift has exceptions
};

// Codes component `comp`'s form through `c` (the encoder writes `form`, the decoder ignores it and
// reads) and sets it on `vc`. `values`: how many values the stream holds, the most a table can need.
// Returns an empty string, or (decoder) what is wrong with the declaration, to follow the stream's
// name: " declares 30 decimal places (at most 22)".
template <class C>
std::string codeValueForm(C& c, ValueFormModels& m, ValueCoder& vc, ScalarType type, uint32_t comp, ValueForm form,
                          uint64_t values) {
  if (c.bit(m.table, !form.table.empty())) {
    if (!vc.codeTable(c, comp, &form.table, values))
      return c.ok() ? " declares an invalid value table (longer than its values, or not ascending)"
                    : " is truncated or corrupt in its value table";
    return {};
  }
  if (isFloatType(type)) {
    uint32_t decimal = form.decimals >= 0;
    decimal = c.bit(m.decimal, decimal);
    if (decimal) {
      const uint32_t e = c.direct(static_cast<uint32_t>(std::max(form.decimals, 0)), 5);
      if (!C::kEncoding && e > ValueCoder::kMaxDecimals)
        return " declares " + std::to_string(e) + " decimal places (at most 22)";
      vc.setDecimals(comp, static_cast<int>(e));
      return {};
    }
    if (type == ScalarType::kFloat64) {
      uint32_t printed = form.printed > 0;
      printed = c.bit(m.printed, printed);
      if (printed) {
        const uint32_t p = c.direct(static_cast<uint32_t>(form.printed), 5);
        if (!C::kEncoding && (p < 1 || p > ValueCoder::kMaxPrintedDigits))
          return " declares " + std::to_string(p) + " printed digits (1 to 17)";
        vc.setPrinted(comp, static_cast<int>(p));
        return {};
      }
    }
  }
  uint32_t has = form.shift > 0;
  has = c.bit(m.shift, has);
  if (!has) return {};
  const uint32_t shift = c.direct(form.shift, 6);
  if (!C::kEncoding && (shift == 0 || shift >= static_cast<uint32_t>(vc.bits())))
    return " declares an invalid shift of " + std::to_string(shift) + " bits";
  const uint32_t exceptions = c.bit(m.exceptions, form.exceptions);
  vc.setShift(comp, static_cast<int>(shift), exceptions != 0);
  return {};
}

}  // namespace gtn::level
