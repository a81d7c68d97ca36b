#include "rail_core/coupling/frames.hpp"

#include <stdexcept>
#include <string>

namespace rail::core::coupling {

namespace {
int checked_capacity(int capacity, const char* what) {
  if (capacity < 0)
    throw std::runtime_error(std::string(what) + ": wheel capacity " + std::to_string(capacity) +
                             " is negative");
  return capacity;
}

template <class Frame>
bool copy_impl(const Frame& src, Frame& dst) {
  if (src.count > static_cast<std::uint32_t>(dst.capacity())) return false;
  static_cast<FrameStamp&>(dst) = static_cast<const FrameStamp&>(src);
  dst.count = src.count;
  for (std::uint32_t i = 0; i < src.count; ++i) dst.wheels[i] = src.wheels[i];
  return true;
}
}  // namespace

WheelStateFrame::WheelStateFrame(int capacity)
    : wheels(static_cast<std::size_t>(checked_capacity(capacity, "WheelStateFrame"))) {}

WrenchFrame::WrenchFrame(int capacity)
    : wheels(static_cast<std::size_t>(checked_capacity(capacity, "WrenchFrame"))) {}

bool copy_frame(const WheelStateFrame& src, WheelStateFrame& dst) { return copy_impl(src, dst); }
bool copy_frame(const WrenchFrame& src, WrenchFrame& dst) { return copy_impl(src, dst); }

}  // namespace rail::core::coupling
