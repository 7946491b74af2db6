// ROS 2 bags (see recording.hpp): rosbag2's directory (metadata.yaml and its storage files), or
// one storage file alone; sqlite3 files through Debian's libsqlite3, MCAP files through
// McapReader. Messages are CDR: sensor_msgs/msg/PointCloud2 (decoded by point_cloud2), or the
// Ouster driver's raw packets with its metadata topic (decoded by ouster).
#include <sqlite3.h>

#include <algorithm>
#include <fstream>
#include <optional>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/mcap.hpp"
#include "lidarsurf/io/point_cloud2.hpp"
#include "message_reader.hpp"
#include "recording_sources.hpp"

namespace lidarsurf::detail {
namespace {

constexpr const char* kPointCloud2 = "sensor_msgs/msg/PointCloud2";
constexpr const char* kOusterPacket = "ouster_sensor_msgs/msg/PacketMsg";  // ouster-ros's raw packets
constexpr const char* kString = "std_msgs/msg/String";

std::string trimmed(std::string s) {
    const auto b = s.find_first_not_of(" \t\r");
    const auto e = s.find_last_not_of(" \t\r");
    s = b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) s = s.substr(1, s.size() - 2);
    return s;
}

// The storage files of a bag, in order. Of metadata.yaml, rosbag2's own layout, only what says
// where the messages are: the storage, the files and their compression.
std::vector<std::filesystem::path> storage_files(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_directory(path, ec)) return {path};
    std::ifstream in(path / "metadata.yaml");
    if (!in) throw IoError((path / "metadata.yaml").string() + ": cannot read");
    std::vector<std::filesystem::path> files;
    std::string line, compression_mode, compression_format;
    bool in_list = false;
    while (std::getline(in, line)) {
        const std::string t = trimmed(line);
        if (in_list && t.rfind("- ", 0) == 0) {
            files.push_back(path / trimmed(t.substr(2)));
            continue;
        }
        in_list = t == "relative_file_paths:";
        if (t.rfind("compression_mode:", 0) == 0) compression_mode = trimmed(t.substr(17));
        if (t.rfind("compression_format:", 0) == 0) compression_format = trimmed(t.substr(19));
    }
    if (!compression_mode.empty() && compression_mode != "NONE")
        throw InvalidInput(path.string() + ": a bag compressed by rosbag2 (" + compression_format + " per " + compression_mode +
                           "): decompress it first (`ros2 bag convert`, or `zstd -d` on each file of a FILE-compressed bag)");
    if (files.empty()) {  // no list: the directory's storage files, by name
        for (const auto& entry : std::filesystem::directory_iterator(path)) {
            const std::string e = lower_extension(entry.path());
            if (e == ".db3" || e == ".mcap") files.push_back(entry.path());
        }
        std::sort(files.begin(), files.end());
        if (files.empty()) throw FormatError(path.string() + ": a ROS 2 bag directory without .db3 or .mcap files");
    }
    for (const auto& f : files)
        if (!std::filesystem::exists(f, ec)) throw IoError(f.string() + ": no such file (listed in " + (path / "metadata.yaml").string() + ")");
    return files;
}

// One sqlite3 storage file of rosbag2: tables topics(id, name, type, serialization_format) and
// messages(id, topic_id, timestamp, data). Opened read-only and immutable: nothing is written
// beside the bag, not even a lock or a journal.
class Db3File {
public:
    explicit Db3File(const std::filesystem::path& path) : path_(path) {
        std::string uri = "file:";
        for (const unsigned char c : std::filesystem::absolute(path).string()) {
            if (std::isalnum(c) || c == '/' || c == '.' || c == '-' || c == '_') {
                uri += static_cast<char>(c);
            } else {
                char hex[4];
                std::snprintf(hex, sizeof hex, "%%%02X", c);
                uri += hex;
            }
        }
        uri += "?immutable=1";
        if (sqlite3_open_v2(uri.c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr) != SQLITE_OK) fail("cannot open");
    }
    ~Db3File() {
        sqlite3_finalize(rows_);
        sqlite3_close(db_);
    }
    Db3File(const Db3File&) = delete;
    Db3File& operator=(const Db3File&) = delete;

    std::vector<TopicSummary> topics() {
        std::vector<TopicSummary> out;
        sqlite3_stmt* s = prepare(
            "SELECT t.name, t.type, t.serialization_format, COUNT(m.id), MIN(m.timestamp), MAX(m.timestamp) "
            "FROM topics t LEFT JOIN messages m ON m.topic_id = t.id GROUP BY t.id ORDER BY t.id");
        int rc;
        while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
            TopicSummary t;
            t.name = text(s, 0);
            t.type = text(s, 1);
            const std::string format = text(s, 2);
            if (format != "cdr") t.type += " (" + format + ")";
            t.messages = static_cast<std::size_t>(sqlite3_column_int64(s, 3));
            t.first_ns = sqlite3_column_int64(s, 4);
            t.last_ns = sqlite3_column_int64(s, 5);
            out.push_back(std::move(t));
        }
        sqlite3_finalize(s);
        if (rc != SQLITE_DONE) fail("cannot list its topics");
        return out;
    }

    /// The topics and their types, without counting their messages.
    std::vector<TopicType> topic_types() {
        std::vector<TopicType> out;
        sqlite3_stmt* s = prepare("SELECT name, type FROM topics ORDER BY id");
        int rc;
        while ((rc = sqlite3_step(s)) == SQLITE_ROW) out.push_back({text(s, 0), text(s, 1)});
        sqlite3_finalize(s);
        if (rc != SQLITE_DONE) fail("cannot list its topics");
        return out;
    }

    /// Starts reading the messages of `topics`, in the order they were written.
    void select(const std::vector<std::string>& topics) {
        sqlite3_finalize(rows_);
        std::string sql = "SELECT m.data, m.id, t.name FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name IN (";
        for (std::size_t i = 0; i < topics.size(); ++i) sql += i ? ",?" : "?";
        rows_ = prepare((sql + ") ORDER BY m.id").c_str());
        for (std::size_t i = 0; i < topics.size(); ++i)
            sqlite3_bind_text(rows_, static_cast<int>(i + 1), topics[i].c_str(), static_cast<int>(topics[i].size()), SQLITE_TRANSIENT);
    }

    /// The next message of the selected topics: its bytes (valid until the next call), its row id
    /// and its topic; false at the end.
    bool next(std::span<const std::uint8_t>& data, std::int64_t& row, std::string& topic) {
        const int rc = sqlite3_step(rows_);
        if (rc == SQLITE_DONE) return false;
        if (rc != SQLITE_ROW) fail("cannot read its messages");
        const auto* bytes = static_cast<const std::uint8_t*>(sqlite3_column_blob(rows_, 0));
        data = std::span<const std::uint8_t>(bytes, bytes ? static_cast<std::size_t>(sqlite3_column_bytes(rows_, 0)) : 0);
        row = sqlite3_column_int64(rows_, 1);
        topic = text(rows_, 2);
        return true;
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw FormatError(path_.string() + ": not a readable ROS 2 sqlite3 bag: " + what + ": " + (db_ ? sqlite3_errmsg(db_) : "out of memory"));
    }
    sqlite3_stmt* prepare(const char* sql) {
        sqlite3_stmt* s = nullptr;
        if (sqlite3_prepare_v2(db_, sql, -1, &s, nullptr) != SQLITE_OK) fail("no rosbag2 tables");
        return s;
    }
    static std::string text(sqlite3_stmt* s, int column) {
        const auto* t = sqlite3_column_text(s, column);
        return t ? reinterpret_cast<const char*>(t) : "";
    }

    std::filesystem::path path_;
    sqlite3* db_ = nullptr;
    sqlite3_stmt* rows_ = nullptr;
};

bool is_mcap(const std::filesystem::path& file) { return lower_extension(file) == ".mcap"; }

// The topics and types of an MCAP file: from its summary, else from a pass over its data.
std::vector<TopicType> mcap_topic_types(const std::filesystem::path& file) {
    McapReader reader(file);
    if (!reader.read_summary_channels()) {
        McapMessage m;
        while (reader.next(m)) {
        }
    }
    std::vector<TopicType> out;
    for (const auto& [id, c] : reader.channels()) out.push_back({c.topic, c.schema_name});
    return out;
}

// The topics of an MCAP file with their counts and spans: from the summary's channels and the
// message indexes when it has both (the chunks are not inflated), else from its messages.
std::vector<TopicSummary> mcap_topics(const std::filesystem::path& file) {
    McapReader reader(file);
    std::map<std::uint16_t, McapChannelStats> stats;
    if (!reader.read_summary_channels() || !reader.index_stats(stats)) {
        stats.clear();
        McapMessage m;
        while (reader.next(m)) stats[m.channel->id].add(m.log_time_ns);
    }
    std::vector<TopicSummary> out;
    for (const auto& [id, c] : reader.channels()) {
        TopicSummary t;
        if (const auto s = stats.find(id); s != stats.end() && s->second.messages > 0) {
            t.messages = s->second.messages;
            t.first_ns = static_cast<std::int64_t>(s->second.first_ns);
            t.last_ns = static_cast<std::int64_t>(s->second.last_ns);
        }
        t.name = c.topic;
        t.type = c.schema_name + (c.message_encoding == "cdr" ? "" : " (" + c.message_encoding + ")");
        out.push_back(std::move(t));
    }
    return out;
}

// The messages of some topics over a bag's storage files, in order.
class Ros2Messages {
public:
    Ros2Messages(const std::vector<std::filesystem::path>& files, std::vector<std::string> topics) : files_(files), topics_(std::move(topics)) {}

    /// The next message's bytes (valid until the next call) and where it is, for messages; false
    /// at the end. topic() is its topic.
    bool next(std::span<const std::uint8_t>& data, std::string& where) {
        for (;;) {
            if (mcap_) {
                McapMessage m;
                if (!mcap_->next(m)) {
                    mcap_.reset();
                    continue;
                }
                if (std::find(topics_.begin(), topics_.end(), m.channel->topic) == topics_.end()) continue;
                topic_ = m.channel->topic;
                if (m.channel->message_encoding != "cdr")
                    throw InvalidInput(mcap_->name() + ": topic " + topic_ + " is encoded as " + m.channel->message_encoding + ", not ROS 2's cdr");
                data = m.data;
                where = mcap_->name() + ": message " + std::to_string(messages_[topic_]++) + " on " + topic_ + " (record at byte " + std::to_string(m.offset) + ")";
                return true;
            }
            if (db3_) {
                std::int64_t row = 0;
                if (!db3_->next(data, row, topic_)) {
                    db3_.reset();
                    continue;
                }
                where = files_[file_ - 1].string() + ": message " + std::to_string(messages_[topic_]++) + " on " + topic_ + " (row " + std::to_string(row) + ")";
                return true;
            }
            if (file_ == files_.size()) return false;
            const auto& f = files_[file_++];
            if (is_mcap(f)) {
                mcap_ = std::make_unique<McapReader>(f);
            } else {
                db3_ = std::make_unique<Db3File>(f);
                db3_->select(topics_);
            }
        }
    }
    const std::string& topic() const { return topic_; }

private:
    const std::vector<std::filesystem::path>& files_;
    std::vector<std::string> topics_;
    std::string topic_;
    std::size_t file_ = 0;
    std::map<std::string, std::size_t> messages_;  // read so far, by topic
    std::unique_ptr<McapReader> mcap_;
    std::unique_ptr<Db3File> db3_;
};

// The topics and types over a bag's storage files.
std::vector<TopicType> topic_types(const std::vector<std::filesystem::path>& files) {
    std::vector<TopicType> topics;
    for (const auto& f : files) {
        for (auto& t : is_mcap(f) ? mcap_topic_types(f) : Db3File(f).topic_types())
            if (type_of(topics, t.name).empty()) topics.push_back(std::move(t));
    }
    return topics;
}

// The messages of some topics, with their types.
class Ros2MessageStream final : public MessageStream {
public:
    Ros2MessageStream(const std::filesystem::path& path, const std::vector<std::string>& topics)
        : files_(storage_files(path)), types_(topic_types(files_)), messages_(files_, topics) {}
    bool next(RawMessage& m) override {
        if (!messages_.next(m.data, m.where)) return false;
        m.topic = messages_.topic();
        m.type = type_of(types_, m.topic);
        m.cdr = true;
        return true;
    }

private:
    std::vector<std::filesystem::path> files_;
    std::vector<TopicType> types_;
    Ros2Messages messages_;
};

// A uint8[] or string message in CDR (ouster_sensor_msgs/msg/PacketMsg, std_msgs/msg/String): its bytes.
std::span<const std::uint8_t> cdr_sized_bytes(std::span<const std::uint8_t> body, const std::string& where) {
    MessageReader r(body, where, MessageReader::Encoding::Cdr);
    return r.bytes(r.scalar<std::uint32_t>());
}

class Ros2BagSource final : public ScanSource {
public:
    Ros2BagSource(const std::filesystem::path& path, const RecordingOptions& options) : path_(path), files_(storage_files(path)) {
        const auto topics = topic_types(files_);
        topic_ = choose_scan_topic(topics, options.topic, kPointCloud2, kOusterPacket, path_.string());
        if (type_of(topics, topic_) == kOusterPacket) sweeps_.emplace(ouster_metadata(topics, options), options.returns);
        messages_ = std::make_unique<Ros2Messages>(files_, std::vector<std::string>{topic_});
    }

    bool next(RecordedScan& scan) override {
        // The scan's stamp is its header's (or its packets'), as in every other recording; the
        // recorder's receive time is not used.
        std::span<const std::uint8_t> data;
        std::string where;
        while (messages_->next(data, where)) {
            if (!sweeps_) {
                scan = decode_point_cloud2(parse_cdr_point_cloud2(data, where), where);
                scan.index = scans_++;
                return true;
            }
            if (sweeps_->add(cdr_sized_bytes(data, where), where)) {
                scan = sweeps_->take();
                scan.index = scans_++;
                return true;
            }
        }
        if (sweeps_ && sweeps_->finish()) {
            scan = sweeps_->take();
            scan.index = scans_++;
            return true;
        }
        return false;
    }

    std::string description() const override {
        if (!sweeps_) return topic_ + " (" + kPointCloud2 + "), ROS 2 bag";
        return topic_ + " (" + describe_ouster(sweeps_->metadata()) + " packets), ROS 2 bag";
    }

private:
    // The driver's metadata topic: a std_msgs/msg/String beside the packets (/ouster/metadata).
    OusterMetadata ouster_metadata(const std::vector<TopicType>& topics, const RecordingOptions& options) {
        if (!options.metadata.empty()) return read_ouster_metadata(options.metadata);
        const std::string name = topic_.substr(0, topic_.rfind('/')) + "/metadata";
        if (type_of(topics, name) == kString) {
            Ros2Messages metadata(files_, {name});
            std::span<const std::uint8_t> data;
            std::string where;
            if (metadata.next(data, where)) {
                auto text = cdr_sized_bytes(data, where);
                if (!text.empty() && text.back() == 0) text = text.first(text.size() - 1);  // the string's NUL
                return parse_ouster_metadata(std::string_view(reinterpret_cast<const char*>(text.data()), text.size()), where);
            }
        }
        throw InvalidArgument(path_.string() + ": Ouster packets on " + topic_ + " but no " + name + " topic: give the sensor's metadata JSON with --metadata");
    }

    std::filesystem::path path_;
    std::vector<std::filesystem::path> files_;
    std::string topic_;
    std::optional<OusterSweeps> sweeps_;
    std::unique_ptr<Ros2Messages> messages_;
    std::size_t scans_ = 0;
};

}  // namespace

bool is_ros2_bag(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return std::filesystem::exists(path / "metadata.yaml", ec);
    const std::string e = lower_extension(path);
    return e == ".db3" || e == ".mcap";
}

std::unique_ptr<ScanSource> open_ros2_bag(const std::filesystem::path& path, const RecordingOptions& options) {
    return std::make_unique<Ros2BagSource>(path, options);
}

std::vector<TopicType> ros2_bag_topic_types(const std::filesystem::path& path) { return topic_types(storage_files(path)); }

std::unique_ptr<MessageStream> open_ros2_messages(const std::filesystem::path& path, const std::vector<std::string>& topics) {
    return std::make_unique<Ros2MessageStream>(path, topics);
}

std::vector<TopicSummary> ros2_bag_topics(const std::filesystem::path& path) {
    std::vector<TopicSummary> out;
    for (const auto& f : storage_files(path)) {
        for (auto& t : is_mcap(f) ? mcap_topics(f) : Db3File(f).topics()) {
            auto same = std::find_if(out.begin(), out.end(), [&](const TopicSummary& o) { return o.name == t.name; });
            if (same == out.end()) {
                out.push_back(std::move(t));
            } else if (t.messages > 0) {  // a topic over several files
                same->first_ns = same->messages ? std::min(same->first_ns, t.first_ns) : t.first_ns;
                same->last_ns = std::max(same->last_ns, t.last_ns);
                same->messages += t.messages;
            }
        }
    }
    return out;
}

}  // namespace lidarsurf::detail
