// team_table_file_name: the rules in team_file_name.hpp, which the README quotes.

#include "ssl_formation/files/team_file_name.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <regex>
#include <string>
#include <vector>

#include "ssl_formation/match/match.hpp"
#include "ssl_formation/models/table_file.hpp"  // still declares it, for the callers

namespace ssl_formation {
namespace {

// What every file name must look like: kept characters, no '_' at either end, at most 64
// before ".bin".
bool safe_file_name(const std::string& name) {
  static const std::regex safe("[a-z0-9-]([a-z0-9_-]{0,62}[a-z0-9-])?\\.bin");
  return std::regex_match(name, safe);
}

TEST(TeamTableFileName, NamesTheCallersAlreadyUse) {
  EXPECT_EQ(team_table_file_name("TIGERs Mannheim"), "tigers_mannheim.bin");
  EXPECT_EQ(team_table_file_name("  tigers mannheim "), "tigers_mannheim.bin");
  EXPECT_EQ(team_table_file_name("ER-Force"), "er-force.bin");
  EXPECT_EQ(team_table_file_name(""), "unknown.bin");
  EXPECT_EQ(team_table_file_name("   "), "unknown.bin");
  EXPECT_EQ(team_table_file_name(" \t\r\n"), "unknown.bin");
}

TEST(TeamTableFileName, AccentsFoldToTheirBaseLetters) {
  EXPECT_EQ(team_table_file_name("RobôCIn"), "robocin.bin");
  EXPECT_EQ(team_table_file_name("Équipe"), "equipe.bin");
  EXPECT_EQ(team_table_file_name("ÀÁÂÃÄÅ àáâãäå"), "aaaaaa_aaaaaa.bin");
  EXPECT_EQ(team_table_file_name("Ççñ ÑÝýÿ"), "ccn_nyyy.bin");
  EXPECT_EQ(team_table_file_name("ÈÉÊË èéêë ÌÍÎÏ ìíîï"), "eeee_eeee_iiii_iiii.bin");
  EXPECT_EQ(team_table_file_name("ÒÓÔÕÖØ òóôõöø ÙÚÛÜ ùúûü"), "oooooo_oooooo_uuuu_uuuu.bin");
  EXPECT_EQ(team_table_file_name("Straße"), "strasse.bin");
  EXPECT_EQ(team_table_file_name("Æsir Œuvre æ œ"), "aesir_oeuvre_ae_oe.bin");
  EXPECT_EQ(team_table_file_name("Þór Ðð"), "thor_dd.bin");
  // Latin Extended-A.
  EXPECT_EQ(team_table_file_name("Łódź"), "lodz.bin");
  EXPECT_EQ(team_table_file_name("Śląsk Żubr Źródło"), "slask_zubr_zrodlo.bin");
  EXPECT_EQ(team_table_file_name("Čeština Žilina Řeka"), "cestina_zilina_reka.bin");
  EXPECT_EQ(team_table_file_name("Győr Szűcs Ő Ű"), "gyor_szucs_o_u.bin");
  EXPECT_EQ(team_table_file_name("Doğuş Işık İstanbul"), "dogus_isik_istanbul.bin");
  EXPECT_EQ(team_table_file_name("Ștefan Țară Şanţ"), "stefan_tara_sant.bin");
  // Decomposed accents (U+0302 after the o) fold as the composed letter does.
  EXPECT_EQ(team_table_file_name("Robo\u0302CIn"), "robocin.bin");
  // Signs of the Latin-1 block that are not letters separate.
  EXPECT_EQ(team_table_file_name("2×3÷4"), "2_3_4.bin");
}

TEST(TeamTableFileName, NamesDifferingOnlyByCaseOrSurroundingSpacesShareAFile) {
  const std::vector<std::vector<std::string>> same = {
      {"TIGERs Mannheim", "tigers mannheim", "TIGERS MANNHEIM", " \tTigers Mannheim\n"},
      {"RobôCIn", "robôcin", "ROBôCIN", "  RobôCIn  "},
      {"ER-Force", "er-force", "Er-Force "},
      {"東京大学", " 東京大学", "東京大学\t"},
      {"\xFF\xFE", " \xFF\xFE "},
  };
  for (const auto& names : same) {
    for (const std::string& name : names) {
      ASSERT_TRUE(same_team_name(name, names.front())) << name;
      EXPECT_EQ(team_table_file_name(name), team_table_file_name(names.front())) << name;
    }
  }
  // Capitals with accents fold to the same letters as the small ones, though same_team_name
  // (which ignores ASCII case only) tells the names apart.
  EXPECT_EQ(team_table_file_name("ROBÔCIN"), "robocin.bin");
}

TEST(TeamTableFileName, NeverAPathAHiddenFileOrDotDot) {
  EXPECT_EQ(team_table_file_name("a/b\\c:d*e?f"), "a_b_c_d_e_f.bin");
  EXPECT_EQ(team_table_file_name("../etc/passwd"), "etc_passwd.bin");
  EXPECT_EQ(team_table_file_name(".hidden"), "hidden.bin");
  EXPECT_EQ(team_table_file_name("Team #1 (B)"), "team_1_b.bin");
  EXPECT_EQ(team_table_file_name("__under_score__"), "under_score.bin");
  EXPECT_EQ(team_table_file_name("a  --  b"), "a_--_b.bin");
  EXPECT_TRUE(safe_file_name(team_table_file_name("..")));
  EXPECT_TRUE(safe_file_name(team_table_file_name("/")));
}

TEST(TeamTableFileName, NothingLeftGivesAStableHashOfTheName) {
  // The 32-bit FNV-1a of the name's bytes, pinned so that a file keeps its name across builds.
  EXPECT_EQ(team_table_file_name("東京大学"), "team-757710f9.bin");
  EXPECT_EQ(team_table_file_name("🤖"), "team-aa0df0be.bin");
  EXPECT_EQ(team_table_file_name("ロボ!"), "team-9527e237.bin");
  EXPECT_EQ(team_table_file_name(".."), "team-a3d4a70d.bin");
  // Distinct such names, distinct files.
  EXPECT_NE(team_table_file_name("東京"), team_table_file_name("大学"));
  EXPECT_NE(team_table_file_name("🤖"), team_table_file_name("🤖🤖"));
  EXPECT_NE(team_table_file_name("!"), team_table_file_name("?"));
}

TEST(TeamTableFileName, VeryLongNamesAreCut) {
  const std::size_t longest = team_file_name_max_length;
  EXPECT_EQ(team_table_file_name(std::string(60000, 'x')), std::string(longest, 'x') + ".bin");
  std::string accents;
  for (int i = 0; i < 30000; ++i) accents += "é";
  EXPECT_EQ(team_table_file_name(accents), std::string(longest, 'e') + ".bin");
  // A cut that ends in a separator drops it; one inside "ß" keeps the half that fits.
  EXPECT_EQ(team_table_file_name(std::string(longest - 1, 'a') + " b"),
            std::string(longest - 1, 'a') + ".bin");
  EXPECT_EQ(team_table_file_name(std::string(longest - 1, 'a') + "ß"),
            std::string(longest - 1, 'a') + "s.bin");
  // Only separators, however many: a hash, not an impossible file name.
  EXPECT_TRUE(safe_file_name(team_table_file_name(std::string(60000, '/'))));
  EXPECT_TRUE(safe_file_name(team_table_file_name(std::string(60000, '\xFF'))));
}

TEST(TeamTableFileName, InvalidUtf8SeparatesLikeAnyOtherCharacter) {
  EXPECT_EQ(team_table_file_name("a\xFF"
                                 "b"),
            "a_b.bin");  // never a UTF-8 byte
  EXPECT_EQ(team_table_file_name("a\x80\x80"
                                 "b"),
            "a_b.bin");                                     // stray continuations
  EXPECT_EQ(team_table_file_name("Robo\xC3"), "robo.bin");  // cut short at the end
  EXPECT_EQ(team_table_file_name("a\xC3Xb"), "a_xb.bin");   // cut short by a letter
  EXPECT_EQ(team_table_file_name("a\xC0\xAF"
                                 "b"),
            "a_b.bin");  // overlong '/'
  EXPECT_EQ(team_table_file_name("a\xE0\x80\xAF"
                                 "b"),
            "a_b.bin");  // overlong '/'
  EXPECT_EQ(team_table_file_name("a\xED\xA0\x80"
                                 "b"),
            "a_b.bin");  // a surrogate
  EXPECT_EQ(team_table_file_name("a\xF4\x90\x80\x80"
                                 "b"),
            "a_b.bin");  // past U+10FFFF
  EXPECT_EQ(team_table_file_name("Rob\xC3\xB4"
                                 "CIn"),
            "robocin.bin");  // well-formed ô
  EXPECT_EQ(team_table_file_name("\xFF\xFE"), team_table_file_name("\xFF\xFE"));
  EXPECT_TRUE(safe_file_name(team_table_file_name("\xFF\xFE")));
}

TEST(TeamTableFileName, EveryNameGivesASafeFileName) {
  // Arbitrary bytes, weighted towards UTF-8 lead and continuation bytes and separators.
  std::uint64_t x = 2024;
  const auto next = [&x] {
    x = x * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<std::uint32_t>(x >> 33);
  };
  const std::string alphabet = "aZ9-_ ./\xC3\xA9\xB4\xC5\x82\xE6\x9D\xB1\xF0\x9F\xA4\x96\xFF";
  for (int i = 0; i < 5000; ++i) {
    std::string name;
    const std::uint32_t length = next() % 90;
    for (std::uint32_t j = 0; j < length; ++j) {
      name +=
          next() % 4 == 0 ? static_cast<char>(next() % 256) : alphabet[next() % alphabet.size()];
    }
    const std::string file = team_table_file_name(name);
    if (trimmed_team_name(name).empty()) {
      EXPECT_EQ(file, "unknown.bin");
    } else {
      EXPECT_TRUE(safe_file_name(file)) << file;
    }
  }
}

}  // namespace
}  // namespace ssl_formation
