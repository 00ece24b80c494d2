// The decision rule (conformity.hpp).
#include "analysis/inspection/conformity.hpp"

#include <cmath>
#include <limits>

namespace springscan::analysis {
namespace {

// A U that is not a number or negative is no bound at all: as wide as can be, so nothing is
// decided on it under the guard band.
double usable_uncertainty(double u) {
  return u >= 0.0 ? u : std::numeric_limits<double>::infinity();  // NaN fails u >= 0
}

}  // namespace

const char* to_string(DecisionRule rule) {
  return rule == DecisionRule::kSimple ? "SIMPLE" : "GUARD_BAND";
}

const char* to_string(Conformity conformity) {
  switch (conformity) {
    case Conformity::kConforming:
      return "CONFORMING";
    case Conformity::kNonconforming:
      return "NONCONFORMING";
    case Conformity::kUndecided:
      return "UNDECIDED";
    case Conformity::kNotJudged:
      break;
  }
  return "NOT_JUDGED";
}

const char* to_string(PartDecision decision) {
  switch (decision) {
    case PartDecision::kPass:
      return "PASS";
    case PartDecision::kFail:
      return "FAIL";
    case PartDecision::kUndecided:
      break;
  }
  return "UNDECIDED";
}

Conformity judge_at_most(double value, double uncertainty, double limit, DecisionRule rule) {
  if (rule == DecisionRule::kSimple) {
    return value <= limit ? Conformity::kConforming : Conformity::kNonconforming;  // NaN: not
  }
  // ISO 14253-1 8.2 and 8.3: the conformance zone is the specification zone reduced by U,
  // the non-conformance zone the outside of it widened by U.
  const double u = usable_uncertainty(uncertainty);
  if (value <= limit - u) return Conformity::kConforming;
  if (value > limit + u) return Conformity::kNonconforming;
  return Conformity::kUndecided;  // NaN value or U included
}

Conformity judge_at_least(double value, double uncertainty, double limit, DecisionRule rule) {
  if (rule == DecisionRule::kSimple) {
    return value >= limit ? Conformity::kConforming : Conformity::kNonconforming;
  }
  const double u = usable_uncertainty(uncertainty);
  if (value >= limit + u) return Conformity::kConforming;
  if (value < limit - u) return Conformity::kNonconforming;
  return Conformity::kUndecided;
}

Conformity worst(Conformity a, Conformity b) {
  return static_cast<int>(a) >= static_cast<int>(b) ? a : b;
}

}  // namespace springscan::analysis
