// ROS 1 bags (see recording.hpp), through Debian's librosbag-storage: it reads the bag's chunks
// (uncompressed, bz2, lz4) and index; the messages' bytes are decoded here.
#include <algorithm>
#include <map>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/point_cloud2.hpp"
#include "recording_sources.hpp"

#ifdef LIDARSURF_HAVE_ROSBAG
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#endif

namespace lidarsurf::detail {

#ifndef LIDARSURF_HAVE_ROSBAG

std::unique_ptr<ScanSource> open_ros1_bag(const std::filesystem::path& path, const RecordingOptions&) {
    throw InvalidInput(path.string() + ": this build of lidarsurf reads no ROS 1 bags: install librosbag-storage-dev "
                       "(scripts/setup.sh does) and build again");
}

std::vector<TopicSummary> ros1_bag_topics(const std::filesystem::path& path) { return open_ros1_bag(path, {}), std::vector<TopicSummary>{}; }
std::vector<TopicType> ros1_bag_topic_types(const std::filesystem::path& path) { return open_ros1_bag(path, {}), std::vector<TopicType>{}; }
std::unique_ptr<MessageStream> open_ros1_messages(const std::filesystem::path& path, const std::vector<std::string>&) {
    return open_ros1_bag(path, {}), nullptr;
}

#else

namespace {

constexpr const char* kPointCloud2 = "sensor_msgs/PointCloud2";
constexpr const char* kOusterPacket = "ouster_ros/PacketMsg";
constexpr const char* kString = "std_msgs/String";

// rosbag throws its own exceptions (and boost's): they become FormatError naming the bag.
template <typename F>
auto guarded(const std::filesystem::path& path, F&& f) {
    try {
        return f();
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        std::string what = e.what();
        if (what.find("unindexed") != std::string::npos)
            what += " (the bag has no index, as when recording was cut short: `rosbag reindex` writes it)";
        throw FormatError(path.string() + ": not a readable ROS 1 bag: " + what);
    }
}

std::vector<std::uint8_t> message_bytes(const rosbag::MessageInstance& m) {
    std::vector<std::uint8_t> buf(m.size());
    ros::serialization::OStream s(buf.data(), static_cast<std::uint32_t>(buf.size()));
    m.write(s);
    return buf;
}

// A uint8[] or string message body (ouster_ros/PacketMsg, std_msgs/String): its length-prefixed bytes.
std::span<const std::uint8_t> sized_bytes(const std::vector<std::uint8_t>& body, const std::string& where) {
    std::uint32_t n = 0;
    if (body.size() < 4) throw FormatError(where + ": a message shorter than its length field");
    std::memcpy(&n, body.data(), 4);
    if (n != body.size() - 4) throw FormatError(where + ": a message whose length field says " + std::to_string(n) + " bytes in " + std::to_string(body.size() - 4));
    return std::span<const std::uint8_t>(body).subspan(4);
}

std::vector<TopicType> topics_of(rosbag::Bag& bag) {
    rosbag::View view(bag);
    std::vector<TopicType> t;
    for (const auto* c : view.getConnections()) t.push_back({c->topic, c->datatype});
    return t;
}

class Ros1BagSource final : public ScanSource {
public:
    Ros1BagSource(const std::filesystem::path& path, const RecordingOptions& options) : path_(path) {
        guarded(path_, [&] {
            bag_.open(path_.string(), rosbag::bagmode::Read);
            const auto topics = topics_of(bag_);
            topic_ = choose_scan_topic(topics, options.topic, kPointCloud2, kOusterPacket, path_.string());
            type_ = type_of(topics, topic_);
            if (type_ == kOusterPacket) sweeps_.emplace(ouster_metadata(topics, options), options.returns);
            view_ = std::make_unique<rosbag::View>(bag_, rosbag::TopicQuery(topic_));
            it_ = view_->begin();
            return 0;
        });
    }

    bool next(RecordedScan& scan) override {
        return guarded(path_, [&] {
            while (it_ != view_->end()) {
                const std::string where = path_.string() + ": message " + std::to_string(message_) + " on " + topic_;
                const auto body = message_bytes(*it_);
                ++it_;
                ++message_;
                if (!sweeps_) {
                    const auto cloud = parse_ros1_point_cloud2(body, where);
                    scan = decode_point_cloud2(cloud, where);
                    scan.index = scans_++;
                    return true;
                }
                if (sweeps_->add(sized_bytes(body, where), where)) {
                    scan = sweeps_->take();
                    ++scans_;
                    return true;
                }
            }
            if (sweeps_ && sweeps_->finish()) {
                scan = sweeps_->take();
                ++scans_;
                return true;
            }
            return false;
        });
    }

    std::string description() const override {
        if (!sweeps_) return topic_ + " (sensor_msgs/PointCloud2), ROS 1 bag";
        return topic_ + " (" + describe_ouster(sweeps_->metadata()) + " packets), ROS 1 bag";
    }

private:
    OusterMetadata ouster_metadata(const std::vector<TopicType>& topics, const RecordingOptions& options) {
        if (!options.metadata.empty()) return read_ouster_metadata(options.metadata);
        // The driver's metadata topic: a std_msgs/String beside the packets (/os_node/metadata).
        const std::string ns = topic_.substr(0, topic_.rfind('/'));
        for (const auto& [t, type] : topics) {
            if (type != kString || t != ns + "/metadata") continue;
            rosbag::View v(bag_, rosbag::TopicQuery(t));
            for (const auto& m : v) {
                const auto body = message_bytes(m);
                const auto text = sized_bytes(body, path_.string() + ": " + t);
                return parse_ouster_metadata(std::string_view(reinterpret_cast<const char*>(text.data()), text.size()), path_.string() + ": " + t);
            }
        }
        throw InvalidArgument(path_.string() + ": Ouster packets on " + topic_ + " but no " + ns +
                              "/metadata topic: give the sensor's metadata JSON with --metadata");
    }

    std::filesystem::path path_;
    rosbag::Bag bag_;
    std::string topic_, type_;
    std::optional<OusterSweeps> sweeps_;
    std::unique_ptr<rosbag::View> view_;
    rosbag::View::iterator it_;
    std::size_t message_ = 0, scans_ = 0;
};

// The messages of some topics, in the bag's time order.
class Ros1MessageStream final : public MessageStream {
public:
    Ros1MessageStream(const std::filesystem::path& path, const std::vector<std::string>& topics) : path_(path) {
        guarded(path_, [&] {
            bag_.open(path_.string(), rosbag::bagmode::Read);
            view_ = std::make_unique<rosbag::View>(bag_, rosbag::TopicQuery(topics));
            it_ = view_->begin();
            return 0;
        });
    }
    bool next(RawMessage& m) override {
        return guarded(path_, [&] {
            if (it_ == view_->end()) return false;
            m.topic = it_->getTopic();
            m.type = it_->getDataType();
            m.where = path_.string() + ": message " + std::to_string(messages_[m.topic]++) + " on " + m.topic;
            body_ = message_bytes(*it_);
            m.data = body_;
            m.cdr = false;
            ++it_;
            return true;
        });
    }

private:
    std::filesystem::path path_;
    rosbag::Bag bag_;
    std::unique_ptr<rosbag::View> view_;
    rosbag::View::iterator it_;
    std::vector<std::uint8_t> body_;
    std::map<std::string, std::size_t> messages_;  // read so far, by topic
};

}  // namespace

std::vector<TopicType> ros1_bag_topic_types(const std::filesystem::path& path) {
    return guarded(path, [&] {
        rosbag::Bag bag;
        bag.open(path.string(), rosbag::bagmode::Read);
        return topics_of(bag);
    });
}

std::unique_ptr<MessageStream> open_ros1_messages(const std::filesystem::path& path, const std::vector<std::string>& topics) {
    return std::make_unique<Ros1MessageStream>(path, topics);
}

std::unique_ptr<ScanSource> open_ros1_bag(const std::filesystem::path& path, const RecordingOptions& options) {
    return std::make_unique<Ros1BagSource>(path, options);
}

std::vector<TopicSummary> ros1_bag_topics(const std::filesystem::path& path) {
    return guarded(path, [&] {
        rosbag::Bag bag;
        bag.open(path.string(), rosbag::bagmode::Read);
        rosbag::View view(bag);
        std::vector<TopicSummary> out;
        for (const auto* c : view.getConnections()) {
            if (std::any_of(out.begin(), out.end(), [&](const TopicSummary& t) { return t.name == c->topic; })) continue;
            TopicSummary t;
            t.name = c->topic;
            t.type = c->datatype;
            rosbag::View one(bag, rosbag::TopicQuery(c->topic));
            t.messages = one.size();
            t.first_ns = static_cast<std::int64_t>(one.getBeginTime().toNSec());
            t.last_ns = static_cast<std::int64_t>(one.getEndTime().toNSec());
            out.push_back(std::move(t));
        }
        return out;
    });
}

#endif

}  // namespace lidarsurf::detail
