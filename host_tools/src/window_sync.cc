#include "mjc/host/window_sync.h"

namespace mjc::host {

bool WindowSync::Level(bool high, std::string* why) {
  if (level_ == (high ? 1 : 0)) return true;
  if (!line_->Set(high, why)) return false;
  if (level_ >= 0) ++edges_;
  level_ = high ? 1 : 0;
  return true;
}

bool WindowSync::OnWindowStart(const protocol::WindowStart& window, std::string* why) {
  ++windows_;
  return Level(window.motion == Motion::kFlexion, why);
}

bool WindowSync::Rest(std::string* why) { return Level(false, why); }

}  // namespace mjc::host
