// The control tick's I/O bound to the simulated plant: the sensor words the plant's
// encoders produce, and the duty and enable line the plant's motor receives.
#pragma once

#include "hal/joint_io.h"
#include "mjc/plant/plant.h"

namespace mjc::hal {

class SimJointIo {
 public:
  explicit SimJointIo(plant::Plant* plant) : plant_(plant) {}

  Sample ISR_Read() {
    Sample s;
    s.motor_count = plant_->MotorCount();
    s.joint_frame = plant_->JointFrame();
    s.tick_overrun = overrun_;
    overrun_ = false;
    return s;
  }

  void ISR_Write(const Actuation& actuation) { actuation_ = actuation; }

  // What the bridge drives over the coming period.
  double duty() const { return actuation_.duty.ToDouble(); }
  bool bridge_enabled() const { return actuation_.bridge_enabled; }

  // Fault injection on the board side: a late tick. (A silent host is the CAN side's
  // to detect: CanNode raises the command timeout.)
  void InjectOverrun() { overrun_ = true; }

 private:
  plant::Plant* plant_;
  Actuation actuation_;
  bool overrun_ = false;
};
static_assert(JointIo<SimJointIo>);

}  // namespace mjc::hal
