// One vocabulary: every program's options are the ones docs/options.md lists for it, the same
// idea has the same name in every program (-o/--output and --overwrite, --from-log, --horizons in
// seconds), old spellings keep working with a one-line note, and every error line reads
// "PROGRAM: error: ...".

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "child_process.hpp"

namespace ssl_formation {
namespace {

using testing::run_to_end;
using testing::TempDir;

const std::filesystem::path producer_program = SSLF_PRODUCER_PATH;
const std::filesystem::path record_program = SSLF_RECORD_PATH;
const std::filesystem::path trainer_program = SSLF_TRAINER_PATH;
const std::filesystem::path predictor_program = SSLF_PREDICTOR_PATH;
const std::filesystem::path evaluate_program = SSLF_EVALUATE_PATH;
const std::filesystem::path options_doc = std::filesystem::path(SSLF_DOCS_DIR) / "options.md";

using OptionNames = std::set<std::string>;

// The long names --help lists ("  -o [ --output ] PATH", "  --grid arg (=auto)").
OptionNames options_in_help(const std::string& help) {
  OptionNames names;
  static const std::regex option_line(R"(^  (?:-\w \[ )?--([a-z0-9-]+))");
  std::istringstream lines(help);
  for (std::string line; std::getline(lines, line);) {
    std::smatch match;
    if (std::regex_search(line, match, option_line)) names.insert(match[1]);
  }
  names.erase("help");
  return names;
}

// Each "## `PROGRAM`" section's options: every --name in the first cell of its tables' rows.
std::map<std::string, OptionNames> options_in_doc(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::map<std::string, OptionNames> sections;
  static const std::regex heading(R"(^## `([a-z -]+)`)");
  static const std::regex name(R"(--([a-z0-9-]+))");
  std::string section;
  for (std::string line; std::getline(file, line);) {
    std::smatch match;
    if (std::regex_search(line, match, heading)) {
      section = match[1];
      continue;
    }
    if (line.rfind("## ", 0) == 0) section.clear();
    if (section.empty() || line.rfind("| `", 0) != 0) continue;
    const std::string cell = line.substr(1, line.find('|', 1) - 1);
    for (auto it = std::sregex_iterator(cell.begin(), cell.end(), name);
         it != std::sregex_iterator(); ++it) {
      sections[section].insert((*it)[1]);
    }
  }
  return sections;
}

std::string joined(const OptionNames& names) {
  std::string text;
  for (const std::string& n : names) text += " --" + n;
  return text;
}

struct ProgramHelp {
  std::string section;  // as docs/options.md heads it
  std::filesystem::path program;
  std::vector<std::string> arguments;
};

TEST(Vocabulary, EveryProgramsOptionsAreTheOnesItsTableInTheOptionsDocumentLists) {
  TempDir dir;
  const auto documented = options_in_doc(options_doc);
  const std::vector<ProgramHelp> programs{
      {"ssl-producer", producer_program, {"--help"}},
      {"ssl-record", record_program, {"--help"}},
      {"ssl-trainer", trainer_program, {"--help"}},
      {"ssl-trainer merge", trainer_program, {"merge", "--help"}},
      {"ssl-predictor", predictor_program, {"--help"}},
      {"ssl-evaluate", evaluate_program, {"--help"}},
  };
  for (const ProgramHelp& p : programs) {
    const auto run = run_to_end(p.program, p.arguments, dir.path(), "help");
    ASSERT_EQ(run.exit_code, 0) << p.section << ": " << run.err;
    const OptionNames in_help = options_in_help(run.out);
    ASSERT_FALSE(in_help.empty()) << p.section;
    ASSERT_TRUE(documented.count(p.section))
        << "docs/options.md has no section ## `" << p.section << "`";
    const OptionNames& in_doc = documented.at(p.section);
    OptionNames undocumented, gone;
    std::set_difference(in_help.begin(), in_help.end(), in_doc.begin(), in_doc.end(),
                        std::inserter(undocumented, undocumented.end()));
    std::set_difference(in_doc.begin(), in_doc.end(), in_help.begin(), in_help.end(),
                        std::inserter(gone, gone.end()));
    EXPECT_TRUE(undocumented.empty())
        << p.section << ": in --help, not in docs/options.md:" << joined(undocumented);
    EXPECT_TRUE(gone.empty()) << p.section
                              << ": in docs/options.md, not in --help:" << joined(gone);
  }
}

TEST(Vocabulary, EveryProgramThatWritesAFileTakesOutputAndOverwrite) {
  TempDir dir;
  for (const auto& arguments :
       std::vector<std::vector<std::string>>{{"--help"}, {"merge", "--help"}}) {
    for (const auto& program :
         {producer_program, record_program, trainer_program, predictor_program, evaluate_program}) {
      if (arguments.front() == "merge" && program != trainer_program) continue;
      const auto run = run_to_end(program, arguments, dir.path(), "help");
      const OptionNames names = options_in_help(run.out);
      EXPECT_TRUE(names.count("output") && names.count("overwrite"))
          << program.filename() << ' ' << arguments.front() << ":" << joined(names);
      EXPECT_NE(run.out.find("-o [ --output ]"), std::string::npos) << program.filename();
    }
  }
}

bool file_is(const std::filesystem::path& path, const std::string& text) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream read;
  read << file.rdbuf();
  return read.str() == text;
}

TEST(Vocabulary, AnOutputThatExistsIsRefusedWithTheOptionThatReplacesItAndLeftAsItWas) {
  TempDir dir;
  const std::string earlier = "an earlier run's results\n";
  std::ofstream(dir / "out.log") << earlier;
  const auto refused =
      run_to_end(producer_program, {"-o", "out.log", "--duration", "1"}, dir.path(), "producer");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("ssl-producer: error: out.log exists: give --overwrite to replace it"),
            std::string::npos)
      << refused.err;
  EXPECT_TRUE(file_is(dir / "out.log", earlier));

  const auto replaced =
      run_to_end(producer_program, {"-o", "out.log", "--duration", "1", "--overwrite"}, dir.path(),
                 "producer");
  ASSERT_EQ(replaced.exit_code, 0) << replaced.err;
  EXPECT_FALSE(file_is(dir / "out.log", earlier));

  // The trainer's -o (a table trained from nothing) and the predictor's CSV alike.
  std::ofstream(dir / "t.bin") << earlier;
  const auto trainer =
      run_to_end(trainer_program, {"--from-log", "out.log", "-o", "t.bin"}, dir.path(), "trainer");
  EXPECT_EQ(trainer.exit_code, 2);
  EXPECT_NE(trainer.err.find("ssl-trainer: error: t.bin exists: give --overwrite"),
            std::string::npos)
      << trainer.err;
  EXPECT_TRUE(file_is(dir / "t.bin", earlier));
  const auto trained =
      run_to_end(trainer_program, {"--from-log", "out.log", "-o", "t.bin", "--overwrite"},
                 dir.path(), "trainer");
  ASSERT_EQ(trained.exit_code, 0) << trained.err;
  std::ofstream(dir / "p.csv") << earlier;
  const auto predictor =
      run_to_end(predictor_program, {"--from-log", "out.log", "--table", "t.bin", "-o", "p.csv"},
                 dir.path(), "predictor");
  EXPECT_EQ(predictor.exit_code, 2);
  EXPECT_TRUE(file_is(dir / "p.csv", earlier));
}

TEST(Vocabulary, HorizonsAreSecondsEverywhereAndTheOldStepCountStillWorksWithANote) {
  TempDir dir;
  ASSERT_EQ(run_to_end(producer_program, {"-o", "m.log", "--duration", "3"}, dir.path(), "producer")
                .exit_code,
            0);
  // 1.5 s at the default 0.5 s step: three steps learned.
  const auto seconds =
      run_to_end(trainer_program, {"--from-log", "m.log", "-o", "a.bin", "--horizons", "1.5"},
                 dir.path(), "trainer");
  ASSERT_EQ(seconds.exit_code, 0) << seconds.err;
  EXPECT_NE(seconds.err.find("3 horizons"), std::string::npos) << seconds.err;
  const auto old =
      run_to_end(trainer_program, {"--from-log", "m.log", "-o", "b.bin", "--horizon", "2"},
                 dir.path(), "trainer");
  ASSERT_EQ(old.exit_code, 0) << old.err;
  EXPECT_NE(old.err.find("ssl-trainer: note: --horizon is now --horizons"), std::string::npos)
      << old.err;
  EXPECT_NE(old.err.find("2 horizons"), std::string::npos) << old.err;
  // Not a whole number of steps: refused, saying why.
  const auto bad = run_to_end(predictor_program,
                              {"--from-log", "m.log", "--table", "a.bin", "--horizons", "0.7"},
                              dir.path(), "predictor");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("ssl-predictor: error: --horizons 0.7: 0.7 s is not a whole number of "
                         "--step 0.5 s"),
            std::string::npos)
      << bad.err;
  // The predictor's CSV holds the horizons asked for: 0.5 and 1 s for --horizons 1.
  const auto csv =
      run_to_end(predictor_program,
                 {"--from-log", "m.log", "--table", "a.bin", "--horizons", "1", "-o", "p.csv"},
                 dir.path(), "predictor");
  ASSERT_EQ(csv.exit_code, 0) << csv.err;
  std::ifstream predictions(dir / "p.csv");
  std::string header, row;
  std::getline(predictions, header);
  std::set<std::string> horizons;
  const auto column = [&header](const std::string& name) {
    std::istringstream cells(header);
    int index = 0;
    for (std::string cell; std::getline(cells, cell, ','); ++index) {
      if (cell == name) return index;
    }
    return -1;
  };
  const int horizon_column = column("horizon_s");
  ASSERT_GE(horizon_column, 0) << header;
  while (std::getline(predictions, row)) {
    std::istringstream cells(row);
    std::string cell;
    for (int i = 0; i <= horizon_column; ++i) std::getline(cells, cell, ',');
    horizons.insert(cell);
  }
  EXPECT_EQ(horizons, (std::set<std::string>{"0.5", "1"}));
}

TEST(Vocabulary, OldSpellingsOfInputsAndOutputsWorkWithANoteForARelease) {
  TempDir dir;
  const auto producer = run_to_end(producer_program, {"--write-log", "m.log", "--duration", "2"},
                                   dir.path(), "producer");
  ASSERT_EQ(producer.exit_code, 0) << producer.err;
  EXPECT_NE(producer.err.find("ssl-producer: note: --write-log is now -o/--output"),
            std::string::npos)
      << producer.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "m.log"));
  const auto evaluate =
      run_to_end(evaluate_program, {"as-real-log", "--from-log", "m.log", "--write-log", "r.log"},
                 dir.path(), "evaluate");
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.err;
  EXPECT_NE(evaluate.err.find("ssl-evaluate: note: --write-log is now -o/--output"),
            std::string::npos)
      << evaluate.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "r.log"));
}

TEST(Vocabulary, EveryErrorLineReadsProgramColonError) {
  TempDir dir;
  struct Case {
    std::filesystem::path program;
    std::vector<std::string> arguments;
    std::string prefix;
  };
  const std::vector<Case> cases{
      {producer_program, {"--cameras", "9"}, "ssl-producer: error: "},
      {record_program, {"--duration", "1"}, "ssl-record: error: "},
      {trainer_program, {"--from-log", "nosuch.log", "-o", "t.bin"}, "ssl-trainer: error: "},
      {predictor_program,
       {"--from-log", "nosuch.log", "--model", "persistence"},
       "ssl-predictor: error: "},
      {evaluate_program,
       {"score", "--from-log", "nosuch.log", "--predictions", "no.csv"},
       "ssl-evaluate: error: "},
      {trainer_program, {"merge", "nosuch.bin", "-o", "m.bin"}, "ssl-trainer: error: "},
  };
  for (const Case& c : cases) {
    const auto run = run_to_end(c.program, c.arguments, dir.path(), "error");
    EXPECT_NE(run.exit_code, 0) << c.program.filename();
    std::istringstream lines(run.err);
    bool found = false;
    for (std::string line; std::getline(lines, line);) {
      if (line.find("error") == std::string::npos) continue;
      EXPECT_EQ(line.rfind(c.prefix, 0), 0u) << c.program.filename() << ": " << line;
      found = true;
    }
    EXPECT_TRUE(found) << c.program.filename() << " printed no error line:\n" << run.err;
  }
}

}  // namespace
}  // namespace ssl_formation
