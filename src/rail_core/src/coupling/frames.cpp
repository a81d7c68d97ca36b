#include "rail_core/coupling/frames.hpp"

#include <stdexcept>
#include <string>

namespace rail::core::coupling {

namespace {
int checkedCapacity(int capacity, const char* what) {
  if (capacity < 0)
    throw std::runtime_error(std::string(what) + ": wheel capacity " + std::to_string(capacity) + " is negative");
  return capacity;
}

template <class Frame>
bool copyImpl(const Frame& src, Frame& dst) {
  if (src.count > static_cast<std::uint32_t>(dst.capacity())) return false;
  static_cast<FrameStamp&>(dst) = static_cast<const FrameStamp&>(src);
  dst.count = src.count;
  for (std::uint32_t i = 0; i < src.count; ++i) dst.wheels[i] = src.wheels[i];
  return true;
}
}  // namespace

WheelStateFrame::WheelStateFrame(int capacity)
    : wheels(static_cast<std::size_t>(checkedCapacity(capacity, "WheelStateFrame"))) {}

WrenchFrame::WrenchFrame(int capacity) : wheels(static_cast<std::size_t>(checkedCapacity(capacity, "WrenchFrame"))) {}

bool copyFrame(const WheelStateFrame& src, WheelStateFrame& dst) { return copyImpl(src, dst); }
bool copyFrame(const WrenchFrame& src, WrenchFrame& dst) { return copyImpl(src, dst); }

}  // namespace rail::core::coupling
