#pragma once
// springscand's configuration: the DaemonConfig text proto (config/springscand.textproto is
// the commented default) turned into settings structs. Defaults live in the C++ structs; the
// file overrides only what it sets (STYLE.md section 4). Every error names the file, line and
// column, the field and the value, e.g.
//   /etc/springscan/springscand.textproto:14:3: modbus.port: 70000 is not in 0..65535

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "daemon/log.hpp"
#include "daemon/page_feed.hpp"
#include "daemon/result_publisher.hpp"
#include "daemon/station.hpp"
#include "proto/springscan.pb.h"

namespace springscan::daemon {

/// One entry of the part catalogue: what the PLC's PART_ID means.
struct PartEntry {
  std::uint16_t part_id = 0;
  std::string name;
  std::string cad_file;           ///< absolute (relative paths resolve against the config)
  v1::AnalysisSettings settings;  ///< overrides only; the pipeline fills in its defaults
};

struct DaemonSettings {
  StationSettings station;
  v1::ScannerConfig scanner;  ///< checked by drivers::check_scanner_config, then passed on as
                              ///< read to drivers::make_scanner (the only way to a driver)
  std::vector<PartEntry> parts;
  std::string model_cache_dir = "/var/cache/springscan";
  LogLevel log_level = LogLevel::kInfo;
  MqttSettings mqtt;  ///< mqtt.station is filled in (the station_name when not set)
  PageSettings http;  ///< the operator page (http { }); off unless configured
};

/// Parses and validates `text`; `file_name` is used in error messages and to resolve relative
/// paths (against its directory).
analysis::Expected<DaemonSettings> parse_daemon_config(const std::string& text,
                                                       const std::string& file_name);

/// Reads `path` and calls parse_daemon_config.
analysis::Expected<DaemonSettings> load_daemon_config(const std::string& path);

}  // namespace springscan::daemon
