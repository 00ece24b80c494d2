#pragma once
// The report's style sheet, embedded in the page (no external file).

namespace springscan::report {

/// CSS for screen and A4 print (@page, page-break rules).
const char* report_css();

}  // namespace springscan::report
