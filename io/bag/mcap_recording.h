// mcap_recording.h: MCAP files (mcap.dev/spec, major version 0), the default storage of ROS 2 bags,
// read as a Recording: front to back in one pass, one chunk in memory at a time.
// - Chunks uncompressed, "zstd" or "lz4" (the LZ4 frame format); a chunk's CRC is checked when the
//   writer stored one (non-zero).
// - topics(), sorted by name: from the summary section (Channel + Schema records, counts from the Message Index
//   records of each chunk, checked against the Statistics record) when the file has one; otherwise a
//   scan of the whole data section at open.
// - Channels with message encoding "cdr" (ROS 2) or "ros1" are topics; a schema "sensor_msgs/msg/Image"
//   is reported as "sensor_msgs/Image". Channels of other encodings (json, protobuf...) are not topics
//   and their messages are stepped over.
// - A file cut short (no footer, a partial record): every complete message before the cut; a cut
//   uncompressed chunk gives the messages wholly inside what is left of it. truncation() says where
//   ("cut at byte 123456 inside a chunk record: no footer; 812 complete messages read").
// - A chunk that does not decompress, fails its CRC or holds a malformed record is skipped and listed in
//   skipped() (the file, the chunk's byte offset, the error, the messages per topic of the Message Index
//   records after it); reading goes on with the next chunk.
// Errors (IoError naming the file and the record's offset): an unknown compression, a top-level
// record whose fields run past its end, a chunk or message larger than 1 GiB.
// Threads: one Recording per thread.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "io/bag/recording.h"

namespace cenote::io {

/// Opens an MCAP file and reads its topics (summary or scan).
/// @throws NotFoundError when the file does not exist, IoError when it is not MCAP or is damaged.
std::unique_ptr<Recording> openMcapRecording(const std::filesystem::path& path);

/// "sensor_msgs/msg/Image" -> "sensor_msgs/Image"; a name without "/msg/" is returned unchanged.
std::string ros1TypeName(const std::string& ros2_type);

}  // namespace cenote::io
