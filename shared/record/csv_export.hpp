#pragma once
// MCAP recording -> one CSV file per channel, for spreadsheets and plotting
// tools. Messages are decoded with the schemas embedded in the file
// (McapReader::decode), so any protobuf type works.
//
// Columns: log_time_s, publish_time_s (ns as exact decimal seconds), then
// every scalar field of the message type in field order, flattened with dotted
// names: nested messages recursed (pose.x_m; cells empty when the message is
// absent), repeated fields as name[0], name[1], ... up to the largest count in
// the file (repeated messages as name[0].field), enums as their value names
// (the number when unknown), bools as true/false, floating point in the
// shortest form that reads back exactly, fields with presence (optional,
// oneof) empty when unset. Bytes fields are left out, or with include_bytes
// given as their length in a column name_bytes. Recursive message types are
// not expanded. Strings are quoted per RFC 4180 when they hold a comma, quote,
// CR or LF; lines end in "\n". A channel that is not protobuf gets the two
// time columns only.
#include <cstdint>
#include <map>
#include <string>
#include <string_view>

namespace inspect::record {

struct CsvExportResult {
  std::map<std::string, std::string> files;  // topic -> CSV path written
  std::map<std::string, uint64_t> rows;      // topic -> data rows (the header not counted)
};

/// Writes `out_dir`/<topic>.csv for every channel of the MCAP file but the 3-D
/// scene's and the image's (foxglove.SceneUpdate, FrameTransforms, Grid, ImageAnnotations:
/// drawings of the others' data) (topic
/// without its leading '/', other '/' as '_'; "_<channel id>" appended when
/// two channels would share a name, and then the key is "<topic>#<id>" for a
/// topic seen twice). Creates `out_dir`. A file cut off (no footer) exports
/// what McapReader reads of it. Throws std::runtime_error naming the file on
/// read, decode or write errors. A topic that starts with `drop_prefix` loses
/// it first (a run of robot1: "/robot1/telemetry" -> telemetry.csv).
CsvExportResult exportCsv(const std::string& mcap_path, const std::string& out_dir, bool include_bytes = false,
                          std::string_view drop_prefix = "");

}  // namespace inspect::record
