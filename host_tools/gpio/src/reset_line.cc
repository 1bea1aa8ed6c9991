#include "mjc/gpio/reset_line.h"

#include <thread>

namespace mjc::gpio {

LineOptions ResetLineOptions(std::string consumer) {
  LineOptions options;
  options.consumer = std::move(consumer);
  options.active_low = true;
  options.open_drain = true;
  options.initially_active = false;
  return options;
}

std::unique_ptr<OutputLine> OpenResetLine(const LineSpec& spec, std::string consumer,
                                          std::string* why) {
  return OpenOutput(spec, ResetLineOptions(std::move(consumer)), why);
}

bool PulseReset(OutputLine& line, std::string* why, std::chrono::nanoseconds low,
                const std::function<void(std::chrono::nanoseconds)>& sleep) {
  if (!line.Set(true, why)) {
    std::string ignored;
    (void)line.Set(false, &ignored);  // leave the board running if it can be
    return false;
  }
  if (sleep) {
    sleep(low);
  } else {
    std::this_thread::sleep_for(low);
  }
  return line.Set(false, why);
}

}  // namespace mjc::gpio
