// Prints where ssl-predictor says each opponent robot will be, one line per step ahead:
//   read-predictions [--group 224.5.23.4:10040] [--interface 127.0.0.1] [--count N]
//                    [--timeout-s S]
// Exits 0 after N predictions, 1 if none came within the timeout.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "ssl_formation/client/predictions.hpp"

int main(int argc, char** argv) {
  std::string group = "224.5.23.4:10040";
  std::string interface = "127.0.0.1";
  int count = 10;
  double timeout_s = 10.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string option = argv[i];
    if (option == "--group")
      group = argv[i + 1];
    else if (option == "--interface")
      interface = argv[i + 1];
    else if (option == "--count")
      count = std::atoi(argv[i + 1]);
    else if (option == "--timeout-s")
      timeout_s = std::atof(argv[i + 1]);
  }
  ssl_formation::client::PredictionReceiver receiver(group, interface);
  const auto timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000));
  for (int received = 0; received < count; ++received) {
    const auto prediction = receiver.receive(timeout);
    if (!prediction) {
      std::fprintf(stderr, "read-predictions: no prediction on %s within %g s\n", group.c_str(),
                   timeout_s);
      return 1;
    }
    for (const auto& step : prediction->steps) {
      std::printf("t=%.3f %s %s +%.1fs:", prediction->t_capture, prediction->model.c_str(),
                  prediction->game_state.c_str(), step.horizon_s);
      for (const auto& robot : step.robots) {
        std::printf(" r%u (%.0f,%.0f) r90=%.0f", robot.robot_id, robot.x_mm, robot.y_mm,
                    robot.radius_90_mm);
      }
      std::printf("\n");
    }
  }
  return 0;
}
