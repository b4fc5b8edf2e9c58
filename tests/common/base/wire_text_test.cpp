#include "ssl_formation/base/wire_text.hpp"

#include <gtest/gtest.h>

#include <string>

namespace ssl_formation {
namespace {

TEST(PrintableWireText, KeepsRealNamesAsTheyAre) {
  EXPECT_EQ(printable_wire_text("TIGERs Mannheim"), "TIGERs Mannheim");
  EXPECT_EQ(printable_wire_text("RobôCIn"), "RobôCIn");
  EXPECT_EQ(printable_wire_text("東京"), "東京");
  EXPECT_EQ(printable_wire_text(""), "");
}

TEST(PrintableWireText, EscapesControlsBadBytesAndDirectionMarks) {
  // A newline that would forge a log line, a terminal escape, a right-to-left override.
  EXPECT_EQ(printable_wire_text("A\nssl-trainer error: fake"), "A\\u{000A}ssl-trainer error: fake");
  EXPECT_EQ(printable_wire_text("\x1b[2J"), "\\u{001B}[2J");
  EXPECT_EQ(printable_wire_text("ab\u202Edc"), "ab\\u{202E}dc");
  EXPECT_EQ(printable_wire_text(std::string("x\0y", 3)), "x\\u{0000}y");
  // Bytes that are no UTF-8: a stray continuation, a cut character, an overlong '/'.
  EXPECT_EQ(printable_wire_text("\x80"), "\\x80");
  EXPECT_EQ(printable_wire_text("\xE6\x9D"), "\\xE6\\x9D");
  EXPECT_EQ(printable_wire_text("\xC0\xAF"), "\\xC0\\xAF");
}

TEST(PrintableWireText, CutsLongTextAndSaysHowLongItWas) {
  const std::string spoofed(59814, 'Y');
  const std::string shown = printable_wire_text(spoofed);
  std::string expected(64, 'Y');
  expected += "…(59814 bytes)";
  EXPECT_EQ(shown, expected);
  // Escapes count as one character each.
  const std::string controls(100, '\x01');
  const std::string cut = printable_wire_text(controls, 3);
  EXPECT_EQ(cut, "\\u{0001}\\u{0001}\\u{0001}…(100 bytes)");
  // Exactly the limit: unchanged.
  EXPECT_EQ(printable_wire_text(std::string(64, 'a')), std::string(64, 'a'));
}

}  // namespace
}  // namespace ssl_formation
