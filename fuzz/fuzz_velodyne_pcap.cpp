// libFuzzer harness for Velodyne recordings: pcaps of data packets (the capture, Ethernet/IPv4/UDP,
// fragments, and the packet decoder of every model with its sweeps) and the calibration YAML. The
// first byte picks the model (low 3 bits), both returns (0x08) and, with 0x40, that the rest is a
// calibration YAML instead of a capture.
#include <cstdio>

#include "fuzz_common.hpp"
#include "lidarsurf/io/pcap.hpp"
#include "lidarsurf/io/velodyne.hpp"

using namespace lidarsurf;

namespace {

VelodyneCalibration calibration(VelodyneModel model) {
    if (auto c = velodyne_factory_calibration(model)) return *c;
    VelodyneCalibration c;  // an HDL-64E's: offsets and the two-point correction in use
    c.name = "fuzz.yaml";
    for (int i = 0; i < 64; ++i) {
        VelodyneLaser l;
        l.vert_correction = (2.0 - 0.4 * i) * M_PI / 180;
        l.rot_correction = (i % 3 - 1) * 0.05;
        l.dist_correction = 1.4;
        l.dist_correction_x = 1.45;
        l.dist_correction_y = 1.38;
        l.two_pt_correction = true;
        l.vert_offset_correction = 0.2;
        l.horiz_offset_correction = i % 2 ? 0.026 : -0.026;
        c.lasers.push_back(l);
    }
    return c;
}

constexpr VelodyneModel kModels[] = {VelodyneModel::VLP16, VelodyneModel::VLP16HiRes, VelodyneModel::VLP32C, VelodyneModel::HDL32E,
                                     VelodyneModel::HDL64E};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    if (data[0] & 0x40) {
        fuzz::expect_typed([&] {
            const VelodyneCalibration c = parse_velodyne_calibration(fuzz::as_view(data + 1, size - 1), "fuzz.yaml");
            fuzz::require(!c.lasers.empty() && c.lasers.size() <= 64, "1 to 64 lasers");
            fuzz::require(c.rings().size() == c.lasers.size(), "a ring a laser");
        });
        return 0;
    }
    const VelodyneModel model = kModels[(data[0] & 7) % 5];
    std::FILE* file = fmemopen(const_cast<std::uint8_t*>(data + 1), size - 1, "rb");
    if (!file) return 0;
    fuzz::expect_typed([&] {
        PcapUdpReader pcap(file, "fuzz.pcap");  // owns and closes the file
        VelodyneSweeps sweeps(model, calibration(model), data[0] & 0x08 ? VelodyneReturns::Both : VelodyneReturns::First);
        UdpDatagram d;
        std::size_t points = 0;
        auto check = [&](const RecordedScan& scan) {
            fuzz::require(scan.cloud.points.size() == scan.times.size() && scan.times.size() == scan.cloud.rings.size(), "one time and ring a point");
            for (const auto& p : scan.cloud.points) fuzz::require(p.allFinite() && p.norm() < 140, "a point beyond the 16-bit range");
            for (float t : scan.times) fuzz::require(std::isfinite(t) && t >= 0, "a time that is not finite or before the stamp");
            fuzz::require(scan.completeness > 0 && scan.completeness <= 1, "completeness in (0, 1]");
            points += scan.cloud.points.size();
        };
        while (pcap.next(d)) {
            if (d.destination_port != 2368) continue;
            if (sweeps.add(d.payload, d.stamp_ns, "fuzz.pcap")) check(sweeps.take());
        }
        if (sweeps.finish()) check(sweeps.take());
        fuzz::require(points <= size, "more points than the capture holds");
    });
    return 0;
}
