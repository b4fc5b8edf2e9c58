#include "ssl_formation/base/wire_text.hpp"

#include <cstdint>
#include <cstdio>

namespace ssl_formation {
inline namespace base {

namespace {

// The length of the well-formed UTF-8 character at the start of `s` and its code point, or 0 for
// a byte that starts none (a stray continuation byte, an overlong form, a surrogate, > U+10FFFF).
std::size_t utf8_character(std::string_view s, char32_t& code) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(s[i]); };
  const unsigned char lead = byte(0);
  if (lead < 0x80) {
    code = lead;
    return 1;
  }
  std::size_t length = 0;
  char32_t min = 0;
  if ((lead & 0xE0) == 0xC0) {
    length = 2;
    code = lead & 0x1F;
    min = 0x80;
  } else if ((lead & 0xF0) == 0xE0) {
    length = 3;
    code = lead & 0x0F;
    min = 0x800;
  } else if ((lead & 0xF8) == 0xF0) {
    length = 4;
    code = lead & 0x07;
    min = 0x10000;
  } else {
    return 0;
  }
  if (s.size() < length) return 0;
  for (std::size_t i = 1; i < length; ++i) {
    if ((byte(i) & 0xC0) != 0x80) return 0;
    code = (code << 6) | (byte(i) & 0x3F);
  }
  if (code < min || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return 0;
  return length;
}

bool shown_as_is(char32_t c) {
  if (c < 0x20 || (c >= 0x7F && c <= 0x9F)) return false;
  if (c == 0x2028 || c == 0x2029 || c == 0xFEFF) return false;
  if ((c >= 0x200B && c <= 0x200F) || (c >= 0x202A && c <= 0x202E) ||
      (c >= 0x2060 && c <= 0x2069)) {
    return false;
  }
  return true;
}

}  // namespace

std::string printable_wire_text(std::string_view raw, std::size_t max_chars) {
  std::string out;
  out.reserve(std::min(raw.size(), max_chars * 4) + 16);
  std::size_t chars = 0;
  std::size_t at = 0;
  while (at < raw.size()) {
    if (chars == max_chars) {
      out += "…(" + std::to_string(raw.size()) + " bytes)";
      return out;
    }
    char32_t code = 0;
    const std::size_t length = utf8_character(raw.substr(at), code);
    char escaped[16];
    if (length == 0) {
      std::snprintf(escaped, sizeof escaped, "\\x%02X", static_cast<unsigned char>(raw[at]));
      out += escaped;
      at += 1;
    } else if (!shown_as_is(code)) {
      std::snprintf(escaped, sizeof escaped, "\\u{%04X}", static_cast<unsigned>(code));
      out += escaped;
      at += length;
    } else {
      out.append(raw, at, length);
      at += length;
    }
    ++chars;
  }
  return out;
}

}  // namespace base
}  // namespace ssl_formation
