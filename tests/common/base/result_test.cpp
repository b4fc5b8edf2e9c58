#include "ssl_formation/base/result.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

namespace ssl_formation {
namespace {

enum class Kind { missing, broken };
struct KindError {
  Kind kind = Kind::missing;
  std::string message;
};

Result<int> half(int n) {
  if (n % 2 != 0) return fail(std::to_string(n) + " is odd");
  return n / 2;
}

Result<void, KindError> check(bool ok) {
  if (!ok) return fail(KindError{Kind::broken, "it is broken"});
  return {};
}

TEST(Result, HoldsAValue) {
  const Result<int> r = half(8);
  ASSERT_TRUE(r.has_value());
  EXPECT_TRUE(static_cast<bool>(r));
  EXPECT_EQ(*r, 4);
  EXPECT_EQ(r.value(), 4);
  EXPECT_EQ(r.value_or(-1), 4);
  EXPECT_TRUE(r == 4);
  EXPECT_FALSE(r == 5);
}

TEST(Result, HoldsAnError) {
  const Result<int> r = half(7);
  ASSERT_FALSE(r.has_value());
  EXPECT_FALSE(static_cast<bool>(r));
  EXPECT_EQ(r.error().message, "7 is odd");
  EXPECT_EQ(r.value_or(-1), -1);
  EXPECT_FALSE(r == 3);
}

TEST(Result, ValueOnAnErrorThrowsItsMessage) {
  const Result<int> r = half(7);
  try {
    (void)r.value();
    FAIL() << "value() did not throw";
  } catch (const BadResultAccess& e) {
    EXPECT_STREQ(e.what(), "7 is odd");
  }
  // A std::runtime_error, so the daemons' top-level handler reports it as any other.
  EXPECT_THROW((void)half(1).value(), std::runtime_error);
  EXPECT_THROW(check(false).value(), std::runtime_error);
}

TEST(Result, TypedErrorsKeepTheirKind) {
  const auto r = check(false);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().kind, Kind::broken);
  EXPECT_EQ(r.error().message, "it is broken");
  EXPECT_TRUE(check(true));
  EXPECT_NO_THROW(check(true).value());
}

TEST(Result, MoveOnlyValuesAndArrow) {
  Result<std::unique_ptr<std::vector<int>>> r = std::make_unique<std::vector<int>>(3, 7);
  ASSERT_TRUE(r);
  EXPECT_EQ((*r)->size(), 3u);
  std::unique_ptr<std::vector<int>> taken = std::move(r).value();
  EXPECT_EQ(taken->at(2), 7);

  Result<std::string> text = std::string("abc");
  EXPECT_EQ(text->size(), 3u);
  Result<std::string> moved = std::move(text);
  EXPECT_EQ(*moved, "abc");
}

// A range-for over the value of a temporary Result: value() && returns by value, so the loop
// does not run over a destroyed Result (caught by the sanitizer build if it did).
TEST(Result, RangeForOverATemporarysValueIsSafe) {
  const auto numbers = [] { return Result<std::vector<int>>(std::vector<int>{1, 2, 3}); };
  int sum = 0;
  for (const int n : numbers().value()) sum += n;
  EXPECT_EQ(sum, 6);
}

TEST(Result, ErrorsPassBetweenResultsOfOtherValues) {
  const auto forward = [](int n) -> Result<std::string> {
    Result<int> h = half(n);
    if (!h) return Unexpected(std::move(h).error());
    return std::to_string(*h);
  };
  EXPECT_EQ(forward(6), std::string("3"));
  const auto odd = forward(5);
  ASSERT_FALSE(odd);
  EXPECT_EQ(odd.error(), Error{"5 is odd"});
}

}  // namespace
}  // namespace ssl_formation
