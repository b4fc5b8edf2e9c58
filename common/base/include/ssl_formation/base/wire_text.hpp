#pragma once
// Text that came over the network (team names, a game controller's or tracker's name and id) is
// untrusted: anybody on a tournament's shared groups can send 60,000 characters, terminal escape
// sequences, newlines that forge log lines or bidirectional overrides that reorder what a reader
// sees. Every such text is passed through printable_wire_text() where it enters the program, so
// that the logs, the status lines, the field view and the table file names all get the same
// short, printable text.

#include <cstddef>
#include <string>
#include <string_view>

namespace ssl_formation {
inline namespace base {

// Longer than any SSL team's name or a UUID.
inline constexpr std::size_t wire_text_max_chars = 64;

// `raw` as printable UTF-8 of at most `max_chars` characters:
// - well-formed UTF-8 characters are kept, except control characters (U+0000-U+001F, U+007F,
//   U+0080-U+009F), line and paragraph separators (U+2028, U+2029) and the invisible direction
//   and format marks (U+200B-U+200F, U+202A-U+202E, U+2060-U+2069, U+FEFF), which are written as
//   "\u{XXXX}";
// - bytes that are not UTF-8 are written as "\xNN";
// - when more would follow, the text ends with "…" and the length of `raw` in bytes
//   ("…(59814 bytes)").
// Text that is printable and short comes back unchanged.
std::string printable_wire_text(std::string_view raw, std::size_t max_chars = wire_text_max_chars);

}  // namespace base
}  // namespace ssl_formation
