#pragma once
// The file a team's table is kept in under the trainer's and the predictor's --table-dir, named
// after the team as the game controller spells it.
//
// How a team name becomes a file name:
//   1. The white space around the name is dropped. An empty name gives "unknown.bin".
//   2. The name is read as UTF-8 and folded to ASCII: letters are lower-cased, and Latin letters
//      with diacritics become their base letters (à-å → a, ç → c, è-ë → e, ì-ï → i, ñ → n,
//      ò-ö and ø → o, ù-ü → u, ý and ÿ → y, ð → d, and Latin Extended-A such as ł → l,
//      ś/ş/š → s, ž → z, č → c, ő → o, ű → u, ğ → g, ı → i, and Romanian's ș → s, ț → t;
//      ß → ss, æ → ae, œ → oe, ĳ → ij, þ → th; capitals alike). Combining accents
//      (U+0300-U+036F) are dropped, so a name typed with decomposed accents folds the same.
//   3. a-z, 0-9 and '-' are kept. Every run of anything else (spaces, '_', '.', '/', other
//      punctuation, other scripts, bytes that are not UTF-8) becomes one '_', and '_' is
//      trimmed from both ends.
//   4. At most the first 64 characters of the result are kept (a '_' the cut leaves at the end
//      is trimmed), and ".bin" is appended.
//   5. A name with nothing left after that (only CJK or emoji, say) gives "team-" and 8 hex
//      digits of the 32-bit FNV-1a hash of its bytes (trimmed, ASCII letters lower-cased), e.g.
//      "team-1a2b3c4d.bin", so that such teams get files of their own (two share one only on a
//      32-bit hash collision).
// Names equal ignoring case and the spaces around them (same_team_name in match.hpp) give the
// same file: "RobôCIn" → "robocin.bin", "  TIGERs Mannheim " → "tigers_mannheim.bin",
// "ER-Force" → "er-force.bin". No name gives a hidden file, a path or "..".

#include <cstddef>
#include <string>
#include <string_view>

namespace ssl_formation {
inline namespace files {

inline constexpr std::size_t team_file_name_max_length = 64;  // before ".bin"

std::string team_table_file_name(std::string_view team);

}  // namespace files
}  // namespace ssl_formation
