#pragma once
// Text helpers of the HTML report: escaping (every string that comes from a report, a file
// name or a part name goes through escape_html), base64 for data: URIs, number formatting.

#include <string>
#include <string_view>

namespace springscan::report {

/// Replaces & < > " ' by character references, so the text is safe in element content and in
/// quoted attribute values. Invalid UTF-8 passes through unchanged (the browser shows U+FFFD).
std::string escape_html(std::string_view text);

/// Standard base64 (RFC 4648 section 4) with padding.
std::string base64(std::string_view bytes);

/// `value` with `decimals` digits after the point; "n/a" for NaN or infinity.
std::string fixed(double value, int decimals);

/// Like fixed() with an explicit sign: "+0.120", "-0.300", "0.000".
std::string signed_fixed(double value, int decimals);

/// A number for SVG coordinates: at most 2 decimals, no trailing zeros.
std::string svg_number(double value);

}  // namespace springscan::report
