#pragma once
// Result<T, E>: a value or the reason there is none, after std::expected (C++23, which g++ 12
// lacks): has_value(), explicit operator bool, *, ->, value(), error(), value_or().
//
// The project's one convention for errors:
//   - An error the caller can handle (a file that will not load, an option text that does not
//     parse, a save that failed) comes back as a Result. Its error says what failed, with the
//     path or the text, so the caller can log it as it is or add what to do about it.
//   - Exceptions only where a program cannot go on: bad options, an unusable table at start,
//     a socket that cannot be set up, or value() called on an error (a programming mistake, or a
//     test that wants to fail loudly).
//   - Dropped input (a datagram that does not decode, a log message of an unknown type) is
//     counted, neither returned nor thrown: one bad packet must not stop a stream.
//
// Error is the error of callers that only need a message; a typed error keeps its kind next to
// the message (TableLoadError). Construct a failure with fail(...):
//
//   Result<Grid> parse(std::string_view text) {
//     if (bad) return fail("grid '" + std::string(text) + "' is not of the form LxW");
//     return Grid(l, w);
//   }
//   if (auto grid = Grid::parse(text)) use(*grid); else log(grid.error().message);

#include <concepts>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>

namespace ssl_formation {
inline namespace base {

// The error of a caller that only needs to know what went wrong.
struct Error {
  std::string message;
  friend bool operator==(const Error&, const Error&) = default;
};

// Thrown by Result::value() on an error; what() is the error's message.
class BadResultAccess : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An error on its way into a Result, as std::unexpected.
template <typename E>
class Unexpected {
 public:
  explicit Unexpected(E error) : error_(std::move(error)) {}
  E& error() & { return error_; }
  const E& error() const& { return error_; }
  E&& error() && { return std::move(error_); }

 private:
  E error_;
};
template <typename E>
Unexpected(E) -> Unexpected<E>;

// fail(TableLoadError{...}) for a typed error, fail("text") for an Error.
template <typename E>
requires(!std::convertible_to<E, std::string>) Unexpected<std::decay_t<E>> fail(E&& error) {
  return Unexpected<std::decay_t<E>>(std::forward<E>(error));
}
inline Unexpected<Error> fail(std::string message) {
  return Unexpected<Error>(Error{std::move(message)});
}

namespace detail {
// The text value() throws with: the error's `message` member, or the error itself if it is text.
template <typename E>
std::string message_of(const E& error) {
  if constexpr (requires { std::string(error.message); }) {
    return std::string(error.message);
  } else if constexpr (std::convertible_to<const E&, std::string>) {
    return std::string(error);
  } else {
    return "Result::value() called on an error";
  }
}
template <typename>
inline constexpr bool is_unexpected = false;
template <typename E>
inline constexpr bool is_unexpected<Unexpected<E>> = true;
}  // namespace detail

template <typename T, typename E = Error>
class [[nodiscard]] Result {
 public:
  using value_type = T;
  using error_type = E;

  // From a value, implicitly, as std::expected: `return grid;`.
  template <typename U = T>
  requires(std::constructible_from<T, U> && !std::same_as<std::remove_cvref_t<U>, Result> &&
           !detail::is_unexpected<std::remove_cvref_t<U>>) Result(U&& value)
      : state_(std::in_place_index<0>, std::forward<U>(value)) {}  // NOLINT

  template <typename G>
  requires std::constructible_from<E, const G&> Result(
      const Unexpected<G>& failure)  // NOLINT: implicit, as std::expected
      : state_(std::in_place_index<1>, failure.error()) {}
  template <typename G>
  requires std::constructible_from<E, G&&> Result(
      Unexpected<G>&& failure)  // NOLINT: implicit, as std::expected
      : state_(std::in_place_index<1>, std::move(failure).error()) {}

  bool has_value() const noexcept { return state_.index() == 0; }
  explicit operator bool() const noexcept { return has_value(); }

  // Unchecked, as std::expected: call only after has_value(). Unlike std::expected, the rvalue
  // overloads here return by value, so `for (auto& x : load().value())` does not dangle (a
  // C++20 range-for does not extend the life of the temporary Result).
  T& operator*() & { return *std::get_if<0>(&state_); }
  const T& operator*() const& { return *std::get_if<0>(&state_); }
  T operator*() && { return std::move(*std::get_if<0>(&state_)); }
  T* operator->() { return std::get_if<0>(&state_); }
  const T* operator->() const { return std::get_if<0>(&state_); }

  // Checked: throws BadResultAccess with the error's message when there is no value.
  T& value() & {
    check();
    return **this;
  }
  const T& value() const& {
    check();
    return **this;
  }
  T value() && {
    check();
    return std::move(*std::get_if<0>(&state_));
  }
  template <typename U>
  T value_or(U&& fallback) const& {
    return has_value() ? **this : static_cast<T>(std::forward<U>(fallback));
  }

  // Unchecked: call only when !has_value().
  E& error() & { return *std::get_if<1>(&state_); }
  const E& error() const& { return *std::get_if<1>(&state_); }
  E error() && { return std::move(*std::get_if<1>(&state_)); }

  template <typename U>
  requires(!std::same_as<std::remove_cvref_t<U>, Result>) friend bool operator==(
      const Result& result, const U& value) {
    return result.has_value() && *result == value;
  }

 private:
  void check() const {
    if (!has_value()) throw BadResultAccess(detail::message_of(error()));
  }

  std::variant<T, E> state_;
};

// Success without a value, or the error.
template <typename E>
class [[nodiscard]] Result<void, E> {
 public:
  using value_type = void;
  using error_type = E;

  Result() = default;  // success
  template <typename G>
  requires std::constructible_from<E, const G&> Result(
      const Unexpected<G>& failure)  // NOLINT: implicit, as std::expected
      : state_(std::in_place_index<1>, failure.error()) {}
  template <typename G>
  requires std::constructible_from<E, G&&> Result(
      Unexpected<G>&& failure)  // NOLINT: implicit, as std::expected
      : state_(std::in_place_index<1>, std::move(failure).error()) {}

  bool has_value() const noexcept { return state_.index() == 0; }
  explicit operator bool() const noexcept { return has_value(); }
  void operator*() const noexcept {}
  // Throws BadResultAccess with the error's message on an error.
  void value() const {
    if (!has_value()) throw BadResultAccess(detail::message_of(error()));
  }

  E& error() & { return *std::get_if<1>(&state_); }
  const E& error() const& { return *std::get_if<1>(&state_); }
  E error() && { return std::move(*std::get_if<1>(&state_)); }

 private:
  std::variant<std::monostate, E> state_;
};

}  // namespace base
}  // namespace ssl_formation
