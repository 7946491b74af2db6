#pragma once
// Internal: the ScanSource of each kind of recording, and the topics of each container.
#include <memory>
#include <vector>

#include "lidarsurf/io/recording.hpp"

namespace lidarsurf::detail {

std::unique_ptr<ScanSource> open_ouster_pcap(const std::filesystem::path& path, const RecordingOptions& options);
std::vector<TopicSummary> pcap_topics(const std::filesystem::path& path);

/// ROS 1 bags, through Debian's librosbag-storage; without it (LIDARSURF_HAVE_ROSBAG unset) they
/// throw InvalidInput saying how to build with it.
std::unique_ptr<ScanSource> open_ros1_bag(const std::filesystem::path& path, const RecordingOptions& options);
std::vector<TopicSummary> ros1_bag_topics(const std::filesystem::path& path);

}  // namespace lidarsurf::detail
