#pragma once
// Internal: reading a serialized ROS message, ROS 1's or ROS 2's CDR.
#include <cstdint>
#include <span>
#include <string>

#include "byte_reader.hpp"
#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::detail {

// Reads a serialized message with every length checked against the buffer: ROS 1 serialization
// (little endian, packed, strings without a terminator) or CDR (ROS 2: either byte order, each
// primitive aligned to its size from the end of the 4-byte encapsulation header, strings ending
// in a NUL that their length counts).
class MessageReader {
public:
    enum class Encoding { Ros1, Cdr };
    MessageReader(std::span<const std::uint8_t> bytes, const std::string& where, Encoding encoding)
        : bytes_(bytes), where_(where), cdr_(encoding == Encoding::Cdr) {
        if (!cdr_) return;
        need(4);
        // Encapsulation kinds: 0 CDR big endian, 1 little endian; 6 and 7 plain XCDR2, which lays
        // out the messages read here the same way (none of their members is wider than 4 bytes).
        const unsigned kind = bytes_[0] * 256u + bytes_[1];
        if (kind != 0 && kind != 1 && kind != 6 && kind != 7)
            throw FormatError(where_ + ": CDR encapsulation kind " + std::to_string(kind) + " (only plain CDR, kinds 0, 1, 6 and 7, is read)");
        big_endian_ = kind % 2 == 0;
        at_ = origin_ = 4;
    }
    template <typename T>
    T scalar() {
        if (cdr_) at_ = origin_ + (at_ - origin_ + sizeof(T) - 1) / sizeof(T) * sizeof(T);
        need(sizeof(T));
        const T v = detail::load<T>(reinterpret_cast<const char*>(bytes_.data() + at_), big_endian_);
        at_ += sizeof(T);
        return v;
    }
    std::string string() {
        const std::uint32_t n = scalar<std::uint32_t>();
        need(n);
        std::size_t length = n;
        if (cdr_) {
            if (n == 0 || bytes_[at_ + n - 1] != 0) throw FormatError(where_ + ": a CDR string without its terminating NUL at byte " + std::to_string(at_));
            --length;
        }
        std::string s(reinterpret_cast<const char*>(bytes_.data() + at_), length);
        at_ += n;
        return s;
    }
    std::span<const std::uint8_t> bytes(std::size_t n) {
        need(n);
        auto s = bytes_.subspan(at_, n);
        at_ += n;
        return s;
    }

    /// std_msgs/Header: ROS 1's has a sequence number and an unsigned second, ROS 2's neither.
    struct Header {
        std::int64_t stamp_ns = 0;
        std::string frame_id;
    };
    Header header() {
        Header h;
        std::int64_t sec = 0;
        if (!cdr_) {
            scalar<std::uint32_t>();  // seq
            sec = scalar<std::uint32_t>();
        } else {
            sec = scalar<std::int32_t>();
        }
        h.stamp_ns = sec * 1000000000 + scalar<std::uint32_t>();
        h.frame_id = string();
        return h;
    }

private:
    void need(std::size_t n) const {
        if (at_ > bytes_.size() || n > bytes_.size() - at_)
            throw FormatError(where_ + ": message truncated: " + std::to_string(n) + " bytes needed at byte " + std::to_string(at_) +
                              " of " + std::to_string(bytes_.size()));
    }
    std::span<const std::uint8_t> bytes_;
    const std::string& where_;
    bool cdr_ = false, big_endian_ = false;
    std::size_t at_ = 0, origin_ = 0;
};

}  // namespace lidarsurf::detail
