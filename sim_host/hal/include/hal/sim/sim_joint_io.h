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
    last_sample_ = s;
    return s;
  }

  void ISR_Write(const Actuation& actuation) { actuation_ = actuation; }

  // What the bridge drives over the coming period.
  double duty() const { return actuation_.duty.ToDouble(); }
  bool bridge_enabled() const { return actuation_.bridge_enabled; }

  // Fault injection on the board side: a late tick. (A silent host is the CAN side's
  // to detect: CanNode raises the command timeout.)
  void InjectOverrun() { overrun_ = true; }

  // The words the last ISR_Read() returned, i.e. exactly what the firmware saw this
  // tick. Fault tests judge a fault's first faulty sample on these (a joint read draws
  // fresh noise, so the plant cannot be asked again), not on the firmware's verdict.
  const Sample& last_sample() const { return last_sample_; }

 private:
  plant::Plant* plant_;
  Actuation actuation_;
  bool overrun_ = false;
  Sample last_sample_;
};
static_assert(JointIo<SimJointIo>);

}  // namespace mjc::hal
