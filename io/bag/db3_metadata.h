// db3_metadata.h: the metadata.yaml rosbag2 writes beside a bag's storage files
// (rosbag2_bagfile_information), as far as cenote reads it:
//   storage_identifier: sqlite3 (another storage is an error; absent: sqlite3)
//   relative_file_paths: the bag's files in recording order (`dive_0.db3`; with compression_mode FILE
//     `dive_0.db3.zstd`, each file compressed whole once the recorder closed it)
//   compression_mode: "" or NONE, FILE or MESSAGE (each message's serialized bytes compressed, the
//     .db3 itself plain); rosbag2 writes them in capitals and reads them in any case, as here
//   compression_format: "" (uncompressed) or zstd, the one compressor rosbag2 ships; another is an
//     error naming it
//   topics_with_message_count (name, type, serialization_format, message_count) and starting_time /
//     duration: the topics of a FILE-compressed bag, whose tables are inside its compressed files.
// Errors: IoError naming metadata.yaml and the field.
// Threads: plain values.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "io/bag/recording.h"

namespace cenote::io {

enum class Db3Compression { kNone, kMessage, kFile };

struct Db3Metadata {
  std::vector<std::filesystem::path> files;  // absolute: the bag folder joined with relative_file_paths
  Db3Compression compression = Db3Compression::kNone;
  // From topics_with_message_count, with the bag's time span as each topic's (first_ns, last_ns);
  // topics of another serialization format than cdr or ros1 left out, as the .db3 reader does.
  std::vector<TopicInfo> topics;
};

/// Reads `bag_folder`/metadata.yaml. @throws IoError naming the file and the field that is wrong.
Db3Metadata readDb3Metadata(const std::filesystem::path& bag_folder);

/// "cdr" is MessageEncoding::kCdr, "ros1" kRos1; false for other serialization formats (not read).
bool db3Encoding(const std::string& serialization_format, MessageEncoding& encoding);

}  // namespace cenote::io
