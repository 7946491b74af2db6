#pragma once
// Internal: the ScanSource of each kind of recording, and the topics of each container.
#include <memory>
#include <span>
#include <vector>

#include "lidarsurf/io/recording.hpp"

namespace lidarsurf::detail {

/// The file name's extension in lower case, with its dot (".mcap").
std::string lower_extension(const std::filesystem::path& path);

struct TopicType {
    std::string name, type;
};

/// The topic scans are read from: `requested` when given (InvalidArgument when it is not there
/// or carries neither type), else the only topic of `cloud_type`, else the only one of
/// `packet_type` (IMU packet topics left out). InvalidArgument when there are several or none.
std::string choose_scan_topic(const std::vector<TopicType>& topics, const std::string& requested, const std::string& cloud_type,
                              const std::string& packet_type, const std::string& where);
/// The type of `topic` in `topics`, empty when absent.
std::string type_of(const std::vector<TopicType>& topics, const std::string& topic);

/// One message of a bag, as its container holds it.
struct RawMessage {
    std::string topic, type;
    std::span<const std::uint8_t> data;  ///< valid until the next message is read
    std::string where;                   ///< the file and the message, for errors
    bool cdr = false;                    ///< ROS 2's CDR, else ROS 1's serialization
};

/// The messages of some topics of a bag, in the order the bag holds them.
class MessageStream {
public:
    virtual ~MessageStream() = default;
    virtual bool next(RawMessage& message) = 0;
};

/// A pcap: Ouster packets when the sensor's metadata JSON is given or beside it, else Velodyne data
/// packets (with a calibration YAML given or beside it, or the model's factory angles).
std::unique_ptr<ScanSource> open_pcap(const std::filesystem::path& path, const RecordingOptions& options);
std::vector<TopicSummary> pcap_topics(const std::filesystem::path& path);

/// ROS 1 bags, through Debian's librosbag-storage; without it (LIDARSURF_HAVE_ROSBAG unset) they
/// throw InvalidInput saying how to build with it.
std::unique_ptr<ScanSource> open_ros1_bag(const std::filesystem::path& path, const RecordingOptions& options);
std::vector<TopicSummary> ros1_bag_topics(const std::filesystem::path& path);
std::vector<TopicType> ros1_bag_topic_types(const std::filesystem::path& path);
std::unique_ptr<MessageStream> open_ros1_messages(const std::filesystem::path& path, const std::vector<std::string>& topics);

/// ROS 2 bags: a directory with metadata.yaml and its .db3 (sqlite3) or .mcap files, or one such file.
bool is_ros2_bag(const std::filesystem::path& path);
std::unique_ptr<ScanSource> open_ros2_bag(const std::filesystem::path& path, const RecordingOptions& options);
std::vector<TopicSummary> ros2_bag_topics(const std::filesystem::path& path);
std::vector<TopicType> ros2_bag_topic_types(const std::filesystem::path& path);
std::unique_ptr<MessageStream> open_ros2_messages(const std::filesystem::path& path, const std::vector<std::string>& topics);

}  // namespace lidarsurf::detail
