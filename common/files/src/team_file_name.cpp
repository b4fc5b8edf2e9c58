#include "ssl_formation/files/team_file_name.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <optional>

#include "ssl_formation/match/match.hpp"

namespace ssl_formation {
inline namespace files {

namespace {

// The Latin letters with diacritics and the ASCII they fold to, by code point ranges in
// increasing order (a code point between two ranges has no fold).
struct LatinFold {
  char32_t first;
  char32_t last;
  std::string_view ascii;
};
constexpr auto latin_folds = std::to_array<LatinFold>({
    // Latin-1 Supplement: capitals, then small letters. × (U+00D7) and ÷ (U+00F7) fold to nothing.
    {0x00C0, 0x00C5, "a"},   // À Á Â Ã Ä Å
    {0x00C6, 0x00C6, "ae"},  // Æ
    {0x00C7, 0x00C7, "c"},   // Ç
    {0x00C8, 0x00CB, "e"},   // È É Ê Ë
    {0x00CC, 0x00CF, "i"},   // Ì Í Î Ï
    {0x00D0, 0x00D0, "d"},   // Ð
    {0x00D1, 0x00D1, "n"},   // Ñ
    {0x00D2, 0x00D6, "o"},   // Ò Ó Ô Õ Ö
    {0x00D8, 0x00D8, "o"},   // Ø
    {0x00D9, 0x00DC, "u"},   // Ù Ú Û Ü
    {0x00DD, 0x00DD, "y"},   // Ý
    {0x00DE, 0x00DE, "th"},  // Þ
    {0x00DF, 0x00DF, "ss"},  // ß
    {0x00E0, 0x00E5, "a"},   // à á â ã ä å
    {0x00E6, 0x00E6, "ae"},  // æ
    {0x00E7, 0x00E7, "c"},   // ç
    {0x00E8, 0x00EB, "e"},   // è é ê ë
    {0x00EC, 0x00EF, "i"},   // ì í î ï
    {0x00F0, 0x00F0, "d"},   // ð
    {0x00F1, 0x00F1, "n"},   // ñ
    {0x00F2, 0x00F6, "o"},   // ò ó ô õ ö
    {0x00F8, 0x00F8, "o"},   // ø
    {0x00F9, 0x00FC, "u"},   // ù ú û ü
    {0x00FD, 0x00FD, "y"},   // ý
    {0x00FE, 0x00FE, "th"},  // þ
    {0x00FF, 0x00FF, "y"},   // ÿ
    // Latin Extended-A: capital and small letter pairs, grouped by base letter.
    {0x0100, 0x0105, "a"},   // Ā ā Ă ă Ą ą
    {0x0106, 0x010D, "c"},   // Ć ć Ĉ ĉ Ċ ċ Č č
    {0x010E, 0x0111, "d"},   // Ď ď Đ đ
    {0x0112, 0x011B, "e"},   // Ē ē Ĕ ĕ Ė ė Ę ę Ě ě
    {0x011C, 0x0123, "g"},   // Ĝ ĝ Ğ ğ Ġ ġ Ģ ģ
    {0x0124, 0x0127, "h"},   // Ĥ ĥ Ħ ħ
    {0x0128, 0x0131, "i"},   // Ĩ ĩ Ī ī Ĭ ĭ Į į İ ı
    {0x0132, 0x0133, "ij"},  // Ĳ ĳ
    {0x0134, 0x0135, "j"},   // Ĵ ĵ
    {0x0136, 0x0138, "k"},   // Ķ ķ ĸ
    {0x0139, 0x0142, "l"},   // Ĺ ĺ Ļ ļ Ľ ľ Ŀ ŀ Ł ł
    {0x0143, 0x014B, "n"},   // Ń ń Ņ ņ Ň ň ŉ Ŋ ŋ
    {0x014C, 0x0151, "o"},   // Ō ō Ŏ ŏ Ő ő
    {0x0152, 0x0153, "oe"},  // Œ œ
    {0x0154, 0x0159, "r"},   // Ŕ ŕ Ŗ ŗ Ř ř
    {0x015A, 0x0161, "s"},   // Ś ś Ŝ ŝ Ş ş Š š
    {0x0162, 0x0167, "t"},   // Ţ ţ Ť ť Ŧ ŧ
    {0x0168, 0x0173, "u"},   // Ũ ũ Ū ū Ŭ ŭ Ů ů Ű ű Ų ų
    {0x0174, 0x0175, "w"},   // Ŵ ŵ
    {0x0176, 0x0178, "y"},   // Ŷ ŷ Ÿ
    {0x0179, 0x017E, "z"},   // Ź ź Ż ż Ž ž
    {0x017F, 0x017F, "s"},   // ſ
    // Latin Extended-B: Romanian's comma-below letters, the correct spelling of ş and ţ there.
    {0x0218, 0x0219, "s"},  // Ș ș
    {0x021A, 0x021B, "t"},  // Ț ț
});
constexpr bool in_order(const auto& folds) {
  for (std::size_t i = 0; i < folds.size(); ++i) {
    if (folds[i].first > folds[i].last) return false;
    if (i > 0 && folds[i - 1].last >= folds[i].first) return false;
  }
  return true;
}
static_assert(in_order(latin_folds), "latin_folds is searched by binary search");

// The ASCII a Latin letter with diacritics folds to; empty for any other code point.
std::string_view latin_fold(char32_t c) {
  const auto after = std::upper_bound(latin_folds.begin(), latin_folds.end(), c,
                                      [](char32_t c, const LatinFold& f) { return c < f.first; });
  if (after == latin_folds.begin()) return {};
  const LatinFold& fold = *(after - 1);
  return c <= fold.last ? fold.ascii : std::string_view{};
}

bool is_combining_mark(char32_t c) { return c >= 0x0300 && c <= 0x036F; }

// The code point UTF-8 encodes at the start of `text` (none if the bytes there are not
// well-formed UTF-8: a stray continuation byte, a sequence cut short, an overlong encoding, a
// surrogate or a value past U+10FFFF) and how many bytes it takes (1 when there is none).
struct CodePoint {
  std::optional<char32_t> value;
  std::size_t length = 1;
};
CodePoint next_code_point(std::string_view text) {
  const auto byte = [&text](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char lead = byte(0);
  if (lead < 0x80) return {lead, 1};
  std::size_t length = 0;
  char32_t value = 0;
  unsigned char low = 0x80;  // the second byte's range, narrowed to exclude what is ill-formed
  unsigned char high = 0xBF;
  if (lead >= 0xC2 && lead <= 0xDF) {
    length = 2;
    value = lead & 0x1F;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    value = lead & 0x0F;
    if (lead == 0xE0) low = 0xA0;   // overlong
    if (lead == 0xED) high = 0x9F;  // surrogates
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    value = lead & 0x07;
    if (lead == 0xF0) low = 0x90;   // overlong
    if (lead == 0xF4) high = 0x8F;  // past U+10FFFF
  } else {
    return {};
  }
  if (text.size() < length) return {};
  for (std::size_t i = 1; i < length; ++i) {
    const unsigned char next = byte(i);
    if (next < (i == 1 ? low : 0x80) || next > (i == 1 ? high : 0xBF)) return {};
    value = value << 6 | (next & 0x3F);
  }
  return {value, length};
}

char ascii_lower(char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; }

// 32-bit FNV-1a of the name with its ASCII letters lower-cased, so that it ignores case as
// same_team_name does.
std::uint32_t name_hash(std::string_view name) {
  std::uint32_t hash = 2166136261u;
  for (const char c : name) {
    hash ^= static_cast<unsigned char>(ascii_lower(c));
    hash *= 16777619u;
  }
  return hash;
}

}  // namespace

std::string team_table_file_name(std::string_view team) {
  team = trimmed_team_name(team);
  if (team.empty()) return "unknown.bin";

  std::string name;
  // A run of anything that is not kept becomes one '_', never a leading one.
  const auto separate = [&name] {
    if (!name.empty() && name.back() != '_') name += '_';
  };
  // Folding only ever appends, so a name already past the cap can stop: what follows is cut.
  for (std::size_t at = 0; at < team.size() && name.size() <= team_file_name_max_length;) {
    const CodePoint c = next_code_point(team.substr(at));
    at += c.length;
    if (!c.value) {
      separate();
      continue;
    }
    const char32_t v = *c.value;
    if ((v >= 'a' && v <= 'z') || (v >= '0' && v <= '9') || v == '-') {
      name += static_cast<char>(v);
    } else if (v >= 'A' && v <= 'Z') {
      name += ascii_lower(static_cast<char>(v));
    } else if (is_combining_mark(v)) {
      // Dropped: a decomposed "ô" is "o" followed by U+0302.
    } else if (const std::string_view ascii = latin_fold(v); !ascii.empty()) {
      name += ascii;
    } else {
      separate();
    }
  }
  if (name.size() > team_file_name_max_length) name.resize(team_file_name_max_length);
  while (!name.empty() && name.back() == '_') name.pop_back();

  if (name.empty()) {
    char hex[9];
    std::snprintf(hex, sizeof hex, "%08x", static_cast<unsigned>(name_hash(team)));
    return "team-" + std::string(hex) + ".bin";
  }
  return name + ".bin";
}

}  // namespace files
}  // namespace ssl_formation
