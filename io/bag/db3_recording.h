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
//   says so. A single .db3 file is read on its own (not a truncation).
// - RecordedMessage::file_offset is the message's row id in its file.
// Errors: NotFoundError for a missing path or a file metadata.yaml lists; IoError naming the file for
// what sqlite cannot read ("file is not a database"), a compressed bag (compression_mode FILE or
// MESSAGE), a storage other than sqlite3.
// Threads: one Recording per thread.
#pragma once

#include <filesystem>
#include <memory>

#include "io/bag/recording.h"

namespace cenote::io {

/// Opens a ROS 2 bag folder or a single .db3 file.
/// @throws NotFoundError, IoError as the header says.
std::unique_ptr<Recording> openDb3Recording(const std::filesystem::path& path);

}  // namespace cenote::io
