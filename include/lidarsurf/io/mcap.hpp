#pragma once
// MCAP files (https://mcap.dev/spec), read from the start as a stream: the messages in file
// order, chunks inflated one at a time (zstd and LZ4 frames through Debian's libzstd and liblz4,
// their CRC checked), so memory holds one chunk, not the recording. The summary section is not
// needed, so files without one are read the same way.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

namespace lidarsurf {

struct McapChannel {
    std::uint16_t id = 0;
    std::string topic;
    std::string message_encoding;  ///< "cdr" for ROS 2
    std::string schema_name;       ///< the message type, "sensor_msgs/msg/PointCloud2"; empty without a schema
    std::string schema_encoding;   ///< "ros2msg", ...
};

struct McapMessage {
    const McapChannel* channel = nullptr;
    std::uint64_t log_time_ns = 0;
    std::uint64_t offset = 0;              ///< byte of its record in the file, or of its chunk's record
    std::span<const std::uint8_t> data;    ///< valid until the next call of next()
};

struct McapChannelStats {
    std::size_t messages = 0;
    std::uint64_t first_ns = UINT64_MAX, last_ns = 0;  ///< log times
    void add(std::uint64_t log_time_ns) {
        ++messages;
        first_ns = std::min(first_ns, log_time_ns);
        last_ns = std::max(last_ns, log_time_ns);
    }
};

class McapReader {
public:
    /// Opens an MCAP file. Throws IoError when it cannot be read and FormatError when it does not
    /// begin with MCAP's magic.
    explicit McapReader(const std::filesystem::path& path);
    /// Reads an open file (fuzzers: an fmemopen'ed buffer); `name` is used in messages. Not owned.
    McapReader(std::FILE* file, std::string name);
    ~McapReader();
    McapReader(const McapReader&) = delete;
    McapReader& operator=(const McapReader&) = delete;

    /// The next message, in file order; false after the data section's end. Throws FormatError
    /// naming the file and the byte where a record's length runs past the file or its chunk, a
    /// chunk's compression is unknown, a chunk inflates to another size than it declares or fails
    /// its CRC, a message names a channel not yet defined, or the file ends before its data end.
    bool next(McapMessage& message);

    /// Reads the channels from the summary section, when the file has one that lists them, and
    /// goes back to the first record; false when it has none (the channels are then met in the
    /// data section). Throws FormatError when the footer or summary is malformed.
    bool read_summary_channels();

    /// The messages of each channel and their span, from the message index records that follow
    /// each chunk, without inflating the chunks; then back to where reading was. False (and
    /// `stats` untouched) when a chunk has no index: read the messages instead.
    bool index_stats(std::map<std::uint16_t, McapChannelStats>& stats);

    /// The channels met so far (all of them once next() has returned false, or after
    /// read_summary_channels() returned true).
    const std::map<std::uint16_t, McapChannel>& channels() const { return channels_; }
    const std::string& name() const { return name_; }

private:
    void start();
    void read_record(std::uint8_t& opcode, std::vector<std::uint8_t>& content, bool skip_chunk = false);
    void start_chunk(std::span<const std::uint8_t> chunk);
    void read_schema_or_channel(std::uint8_t opcode, std::span<const std::uint8_t> content, const std::string& where);

    std::FILE* file_ = nullptr;
    bool owned_ = false;
    std::string name_;
    std::uint64_t size_ = 0, at_ = 0;  // file size and position
    std::vector<std::uint8_t> record_, buffer_;  // the last top-level record; inflated chunks
    std::span<const std::uint8_t> chunk_;           // the records of the current chunk (in record_ or buffer_)
    std::uint64_t chunk_offset_ = 0;
    std::size_t chunk_at_ = 0;         // next record inside chunk_
    bool ended_ = false;
    std::map<std::uint16_t, std::string> schemas_;           // id -> name
    std::map<std::uint16_t, std::string> schema_encodings_;  // id -> encoding
    std::map<std::uint16_t, McapChannel> channels_;
};

}  // namespace lidarsurf
