// libFuzzer harness for pcaps of Ouster packets: the capture (libpcap), the Ethernet/IPv4/UDP
// headers and IPv4 fragment reassembly, and the Ouster packet decoder of every profile. The first
// byte picks the profile of the sensor the packets are decoded for; the rest is the capture.
#include <cstdio>

#include "fuzz_common.hpp"
#include "lidarsurf/io/ouster.hpp"
#include "lidarsurf/io/pcap.hpp"

using namespace lidarsurf;

namespace {

const char* kProfiles[] = {"LEGACY", "RNG19_RFL8_SIG16_NIR16", "RNG19_RFL8_SIG16_NIR16_DUAL", "RNG15_RFL8_NIR8", "FUSA_RNG15_RFL8_NIR8_DUAL"};

OusterMetadata sensor(int profile) {
    // 8 beams, 64 columns a frame, 16 a packet (the seeds of fuzz/corpus/ are made for it).
    std::string json = "{\"beam_altitude_angles\":[15,10,5,0,-5,-10,-15,-20],\"beam_azimuth_angles\":[1,-1,1,-1,1,-1,1,-1],"
                       "\"lidar_mode\":\"64x10\",\"lidar_origin_to_beam_origin_mm\":15,\"data_format\":{\"pixels_per_column\":8,"
                       "\"columns_per_packet\":16,\"columns_per_frame\":64,\"column_window\":[0,63],\"udp_profile_lidar\":\"";
    json += kProfiles[profile];
    json += "\"}}";
    return parse_ouster_metadata(json, "fuzz.json");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const int profile = data[0] % 5;
    static const OusterMetadata metadata[5] = {sensor(0), sensor(1), sensor(2), sensor(3), sensor(4)};
    std::FILE* file = fmemopen(const_cast<std::uint8_t*>(data + 1), size - 1, "rb");
    if (!file) return 0;
    fuzz::expect_typed([&] {
        PcapUdpReader pcap(file, "fuzz.pcap");  // owns and closes the file
        OusterSweeps sweeps(metadata[profile], data[0] & 0x80 ? OusterReturns::Both : OusterReturns::First);
        UdpDatagram d;
        std::size_t points = 0;
        auto check = [&](const RecordedScan& scan) {
            fuzz::require(scan.cloud.points.size() == scan.times.size() && scan.times.size() == scan.cloud.rings.size(), "one time and ring a point");
            for (const auto& p : scan.cloud.points) fuzz::require(p.allFinite() && p.norm() < 2100, "a point beyond the 20-bit range");
            for (float t : scan.times) fuzz::require(std::isfinite(t), "a time that is not finite");
            fuzz::require(scan.completeness > 0 && scan.completeness <= 1, "completeness in (0, 1]");
            points += scan.cloud.points.size();
        };
        while (pcap.next(d)) {
            fuzz::require(d.payload.size() <= 65535, "a datagram beyond 64 KiB");
            if (d.destination_port != 7502) continue;
            if (sweeps.add(d.payload, "fuzz.pcap")) check(sweeps.take());
        }
        if (sweeps.finish()) check(sweeps.take());
        fuzz::require(points <= 2 * size, "more points than the capture holds");
    });
    return 0;
}
