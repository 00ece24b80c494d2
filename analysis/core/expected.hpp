#pragma once
// A value or an error message: how expected failures (bad input, too few points, no
// convergence) come back from library code, which neither prints nor aborts (STYLE.md §5).

#include <string>
#include <utility>
#include <variant>

namespace springscan::analysis {

/// An error that the caller can show as one line: what failed, where, and the value seen.
struct Error {
  std::string message;
};

/// Holds either a T or an Error. Check `ok()` (or `if (result)`) before `value()`.
template <typename T>
class Expected {
 public:
  Expected(T value) : state_(std::move(value)) {}      // NOLINT: implicit by design
  Expected(Error error) : state_(std::move(error)) {}  // NOLINT: implicit by design

  bool ok() const { return std::holds_alternative<T>(state_); }
  explicit operator bool() const { return ok(); }

  T& value() & { return std::get<T>(state_); }
  const T& value() const& { return std::get<T>(state_); }
  T&& value() && { return std::get<T>(std::move(state_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

  const Error& error() const { return std::get<Error>(state_); }
  const std::string& message() const { return error().message; }

 private:
  std::variant<T, Error> state_;
};

/// Shorthand for returning an error: `return fail("scan.ply: line 12: bad vertex");`
inline Error fail(std::string message) { return Error{std::move(message)}; }

}  // namespace springscan::analysis
