#pragma once
// The operator page itself: one HTML document with its style and script inline (no external
// resource, like report.html). The script opens the event stream (/events), renders each
// snapshot (page_text.hpp page_snapshot_json) with textContent only, so no text from a report
// can become markup, and reconnects by itself (the stream's retry: 2 s).

namespace springscan::daemon {

/// The page, as served at "/". A static string: the same for every request.
const char* operator_page_html();

}  // namespace springscan::daemon
