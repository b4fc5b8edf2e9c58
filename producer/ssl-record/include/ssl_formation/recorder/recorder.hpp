#pragma once
// ssl-record's work: captures a live multicast feed into an official SSL log file (.log or
// .log.gz), so a match can be replayed (ssl-producer --replay) or trained from later.
//
// Every datagram that decodes as an SSL_WrapperPacket is written as a type-4 message, byte for
// byte as received, with its receive time (Unix time, ns). Datagrams that do not decode are
// counted and left out: the file then holds only what every log player and our reader accept.
// SIGINT, SIGTERM, --duration and --count all end with a complete, valid file.

#include <cstdint>
#include <string>

#include "ssl_formation/app/options.hpp"
#include "ssl_formation/net/multicast.hpp"

namespace ssl_formation::recorder {

struct RecordOptions {
  app::NetworkOptions network;
  app::DaemonOptions daemon;  // --ready-file: written once the group is joined
  std::string output;
  bool overwrite = false;
  bool index = false;
  double duration_s = 0.0;
  std::uint64_t count = 0;
  double status_interval_s = 5.0;
  int receive_buffer_bytes = net::kDefaultReceiveBufferBytes;
  bool verbose = false;
};

// Records until a signal, --duration or --count; returns the exit status. Throws
// app::UsageError for bad options.
int run_record(const RecordOptions& options);

}  // namespace ssl_formation::recorder
