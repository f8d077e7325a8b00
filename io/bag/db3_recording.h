// db3_recording.h: the sqlite3 storage of ROS 2 bags (rosbag2 before MCAP became the default), read as a
// Recording. A bag is a folder with `metadata.yaml` (rosbag2_bagfile_information: its
// relative_file_paths, in recording order) and one or more `.db3` files, each with the tables
// `topics(id, name, type, serialization_format, ...)` and `messages(id, topic_id, timestamp, data)`.
// - Messages come file by file, each file in timestamp order (then row id): one row in memory at a time.
// - topics(), sorted by name: the union of the files' topics tables (a topic by its name and type), counts and time spans
//   from the messages tables. Types "sensor_msgs/msg/Image" are reported as "sensor_msgs/Image";
//   serialization_format "cdr" is MessageEncoding::kCdr, "ros1" kRos1; other formats are not topics.
// - A folder without metadata.yaml (the recorder writes it last, so a recording cut short has none):
//   its .db3 files in the order of their index suffix (dive_0.db3, dive_1.db3, ...), and truncation()
//   says so. A single .db3 file is read on its own (not a truncation). Compression is told without
//   metadata too: dive_0.db3.zstd files (a FILE-compressed recorder compresses each file it closes,
//   the open one stays plain) are decompressed at open for their topics and again when read; a message
//   whose bytes begin with zstd's magic number (28 B5 2F FD; CDR begins 00 0x) is decompressed.
// - RecordedMessage::file_offset is the message's row id in its file.
// - Compressed bags (db3_metadata.h: compression_format zstd): compression_mode MESSAGE, each message's
//   bytes decompressed as it is read; compression_mode FILE (files dive_0.db3.zstd), each file
//   decompressed when reading reaches it into a temporary file in TMPDIR (else /tmp; as large as the
//   plain .db3), which sqlite reads and which is removed when the file is done (one at a time); its
//   topics and counts then come from metadata.yaml, each topic spanning the bag's time span.
// Errors: NotFoundError for a missing path or a file metadata.yaml lists; IoError naming the file for
// what sqlite cannot read ("file is not a database"), a compression_format other than zstd, data zstd
// rejects (a message: its row id and topic), a storage other than sqlite3; ResourceExhaustedError
// when the decompressed copy does not fit in TMPDIR.
// Threads: one Recording per thread.
#pragma once

#include <filesystem>
#include <memory>

#include "io/bag/recording.h"

namespace cenote::io {

/// True for a rosbag2 sqlite3 file's name: "dive_0.db3", or "dive_0.db3.zstd" (compressed by file).
bool isDb3FileName(const std::filesystem::path& path);

/// Opens a ROS 2 bag folder or a single .db3 file.
/// @throws NotFoundError, IoError as the header says.
std::unique_ptr<Recording> openDb3Recording(const std::filesystem::path& path);

}  // namespace cenote::io
