#pragma once
// The decision rule (ISO 14253-1; VDA 5, ILAC G8 guard bands): one value against one limit,
// with the value's expanded uncertainty U (k = 2). Under GUARD_BAND a value conforms when it
// lies inside its limit by more than U, does not conform when it lies outside by more than U,
// and in between the station cannot tell: UNDECIDED. SIMPLE compares the value alone (U is
// ignored), as the verdict did before U existed. The verdict (verdict.hpp) judges every
// characteristic through these two functions, so a rule is applied in one place only.
//
// A value that is not a number, or a U that is not a number or negative, cannot be placed
// against the limit: GUARD_BAND says UNDECIDED (a re-measure, then a person, decides), SIMPLE
// says NONCONFORMING (as before: a value that cannot be compared is not a pass).
//
// Thread safety: pure functions.

namespace springscan::analysis {

enum class DecisionRule {
  kGuardBand,  ///< ISO 14253-1: inside (outside) by more than U, else undecided (default)
  kSimple,     ///< the value alone against the limit; U ignored
};

/// One characteristic against its limit. Ordered from best to worst (worst() relies on it).
enum class Conformity {
  kNotJudged,      ///< no limit applies (a rule switched off, a closed hem)
  kConforming,     ///< inside the limit (by more than U under GUARD_BAND)
  kUndecided,      ///< within U of the limit, or not measured: the station cannot tell
  kNonconforming,  ///< outside the limit (by more than U under GUARD_BAND)
};

/// The part: PASS when every judged characteristic conforms, FAIL when any does not (or a
/// health rule fails), else UNDECIDED.
enum class PartDecision {
  kPass,
  kFail,
  kUndecided,
};

const char* to_string(DecisionRule rule);      ///< "GUARD_BAND", "SIMPLE"
const char* to_string(Conformity conformity);  ///< "CONFORMING", ... ("NOT_JUDGED")
const char* to_string(PartDecision decision);  ///< "PASS", "FAIL", "UNDECIDED"

/// An upper limit: `value` <= `limit` conforms (value: a magnitude such as |springback|, mm or
/// deg; `uncertainty`: its expanded U in the same unit).
Conformity judge_at_most(double value, double uncertainty, double limit, DecisionRule rule);

/// A lower limit: `value` >= `limit` conforms (a least curl radius).
Conformity judge_at_least(double value, double uncertainty, double limit, DecisionRule rule);

/// The worse of two (NONCONFORMING > UNDECIDED > CONFORMING > NOT_JUDGED).
Conformity worst(Conformity a, Conformity b);

}  // namespace springscan::analysis
