#pragma once
// The pages of `springscan msa` (report/msa.hpp has the studies): one self-contained HTML file
// each, inline SVG and CSS, no script and nothing fetched. A table of the characteristics with
// their figures and verdicts, then per characteristic its charts: for type 1 the run chart
// (reference, reference +- 0.1 T, mean) and the histogram; for type 3 the trials part by part.

#include <string>
#include <vector>

#include "proto/springscan.pb.h"

namespace springscan::report {

struct MsaPageInfo {
  std::string title;                 ///< empty: "springscan msa type 1" / "... type 3"
  std::vector<std::string> sources;  ///< the paths the reports were read from
  std::string first_utc, last_utc;   ///< the reports' time span
};

std::string render_type1_html(const v1::MsaType1Study& study, const MsaPageInfo& info);
std::string render_type3_html(const v1::MsaType3Study& study, const MsaPageInfo& info);

}  // namespace springscan::report
