#pragma once
// A PredictionOutput that keeps what a daemon driven in-process would have multicast and printed.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "formation_prediction.pb.h"
#include "ssl_formation/predictor/predictor_daemon.hpp"

namespace ssl_formation::testing {

class RecordedOutput final : public predictor::PredictionOutput {
 public:
  void send(std::span<const std::byte> datagram) override {
    datagrams.emplace_back(reinterpret_cast<const char*>(datagram.data()), datagram.size());
  }
  void print(std::string_view line) override { lines.emplace_back(line); }
  std::uint64_t sent() const override { return datagrams.size(); }

  // The datagrams decoded (throws if one is not a FormationPrediction).
  std::vector<proto::FormationPrediction> messages() const {
    std::vector<proto::FormationPrediction> out;
    for (const std::string& bytes : datagrams) {
      proto::FormationPrediction message;
      if (!message.ParseFromString(bytes)) throw std::runtime_error("not a FormationPrediction");
      out.push_back(std::move(message));
    }
    return out;
  }

  std::vector<std::string> datagrams;
  std::vector<std::string> lines;
};

}  // namespace ssl_formation::testing
