// libFuzzer harness for sensor files (JSON): a sensor that parses is valid and round-trips.
#include "fuzz_common.hpp"
#include "lidarsurf/sim/sensor_model.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::expect_typed([&] {
        const sim::SensorModel sensor = sim::SensorModel::from_json(fuzz::as_view(data, size));
        const sim::SensorModel again = sim::SensorModel::from_json(sensor.to_json());
        fuzz::require(again.to_json() == sensor.to_json(), "sensor JSON does not round-trip");
    });
    return 0;
}
