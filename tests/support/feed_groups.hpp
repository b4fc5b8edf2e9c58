#pragma once
// The multicast groups a test's programs use. Our daemons join or send four feeds, each on a
// group whose default is the real one: vision 224.5.23.2:10006, referee 224.5.23.1:10003,
// tracker 224.5.23.2:10010, predictions 224.5.23.4:10040. A game controller, an SSL-Vision feed
// or scripts/demo.sh running on the same machine would reach a test that left one of them at its
// default (and a test's replay would reach them), so no test does: ChildProcess gives each feed a
// program takes and its test did not set a group of its own (FeedGroups::complete). Programs that
// share a feed are given the same group by their test (new_group(), or one FeedGroups for all).
// Everything stays on loopback: --interface 127.0.0.1 unless the test says otherwise.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ssl_formation::testing {

// A UDP port no socket on this machine uses right now (the kernel picks it), and a random
// administratively scoped multicast group, so tests that ctest runs in parallel never share
// traffic. Both stay on loopback: every program in the tests sends and joins on 127.0.0.1.
std::uint16_t free_udp_port();
std::string unique_group(std::uint16_t port);  // "239.255.x.y:PORT"

// "239.255.x.y:PORT" on a port nobody uses: one feed of one test.
inline std::string new_group() { return unique_group(free_udp_port()); }

// One group of the test's own for each feed.
struct FeedGroups {
  std::string vision = new_group();
  std::string referee = new_group();
  std::string tracker = new_group();
  std::string predictions = new_group();

  // `arguments` for `program`, plus --vision-address, --referee-address, --tracker-address,
  // --prediction-address (ssl-predictor only) with these groups and --interface 127.0.0.1, each
  // where the program takes it and `arguments` does not set it. The programs: ssl-producer,
  // ssl-trainer, ssl-predictor, ssl-record; any other program's arguments come back unchanged,
  // and so do a subcommand's (`ssl-trainer merge ...`), which joins and sends nothing.
  std::vector<std::string> complete(const std::filesystem::path& program,
                                    std::vector<std::string> arguments) const {
    const std::string name = program.filename().string();
    const bool predictor = name == "ssl-predictor";
    if (!predictor && name != "ssl-producer" && name != "ssl-trainer" && name != "ssl-record") {
      return arguments;
    }
    if (!arguments.empty() && arguments.front().rfind('-', 0) != 0) return arguments;
    const auto add_unless_set = [&](const std::string& option, const std::string& value) {
      for (const std::string& argument : arguments) {
        if (argument == option || argument.rfind(option + "=", 0) == 0) return;
      }
      arguments.push_back(option);
      arguments.push_back(value);
    };
    add_unless_set("--vision-address", vision);
    add_unless_set("--referee-address", referee);
    add_unless_set("--tracker-address", tracker);
    if (predictor) add_unless_set("--prediction-address", predictions);
    add_unless_set("--interface", "127.0.0.1");
    return arguments;
  }
};

}  // namespace ssl_formation::testing
