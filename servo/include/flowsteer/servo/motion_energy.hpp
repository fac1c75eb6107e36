#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "flowsteer/base/camera.hpp"
#include "flowsteer/servo/control.hpp"
#include "flowsteer/servo/flow_field.hpp"
#include "flowsteer/servo/ground.hpp"

namespace flowsteer::servo {

// What a pixel shows, as Blumberg's steering needs it (Blumberg 1997, "The Motion Energy
// Approach"). The paper renders the floor as one constant-coloured polygon and the background
// black, so that po(i, j) = 1 for a non-black pixel marks "mass" (something standing in the
// way) and the floor gives no energy; the ridge is the first non-floor pixel of each column.
enum class PixelClass : std::uint8_t {
  floor,  // the ground: no mass, and part of the ridge's floor
  mass,   // an object: po(i, j) = 1
  empty,  // sky or far background: no mass, not floor
};

// Classes from the simulator's object ids: ids >= 0 are objects (mass), kGroundId the floor,
// any other negative id (the sky) empty. `ids` and `out` have one entry per pixel.
void classify_by_ids(std::span<const std::int32_t> ids, std::span<PixelClass> out);

// Classes without object ids, for a real camera: the floor is what the flat-ground test of
// ground.hpp marks (depth test with depth, else the derotated flow's); above the horizon a
// pixel whose derotated flow is slower than still_flow (normalised units per second: far
// background, sky) is empty; every other pixel is mass. `ground_mask` is scratch with one entry
// per pixel.
void classify_by_ground(const FlowField& derotated, const base::CameraMount& mount,
                        double speed_mps, const GroundRemovalOptions& ground, double still_flow,
                        std::span<std::uint8_t> ground_mask, std::span<PixelClass> out);

struct MotionEnergyOptions {
  // fw: the weight of the frame difference against the mass term (Blumberg 1997, FM_ijt).
  double flow_weight = 0.5;
  // K of bearingToSteer = K (Σ_left FM − Σ_right FM), with each sum taken as the mean energy of
  // its half (in [0, 1]) so that K does not depend on the resolution: rad/s per unit.
  double steer_gain = 3.0;
  // Turn rate per radian of bearing when steering to the goal or to an opening.
  double goal_gain = 1.5;
  // Head-on case: the mean energy of the whole image above this, with the halves' difference
  // below head_on_balance of their sum, and the agent picks a side and turns.
  double head_on_energy = 0.3;
  double head_on_balance = 0.15;
  // The danger zone: the floor in front of the agent up to danger_distance_m ahead and within
  // half the agent's width (set by the caller) on either side, seen at the bottom centre of the
  // image. More than danger_fraction of its pixels with mass is an obstacle dangerously close.
  double danger_distance_m = 1.5;
  double danger_fraction = 0.05;
  // Corners of the ridge: a change of ridge height by more than corner_rise (a fraction of
  // the rows from the bottom to the horizon) over corner_step (a fraction of the width).
  double corner_step = 0.05;
  double corner_rise = 0.25;
  // The free-path test looks at the floor along the straight path to the goal, up to this far.
  double free_path_range_m = 10.0;
};

// An opening of the ridge: between a left and a right corner (image columns, inclusive).
struct Opening {
  int first_col = 0;
  int last_col = 0;
  double bearing_rad = 0.0;  // of its middle, positive to the right
};

enum class MotionEnergyMode : std::uint8_t {
  goal,     // a free path to the goal: steer to it
  opening,  // no free path: steer by the energy difference, drawn to the opening nearest the goal
  energy,   // no free path and no opening: steer by the energy difference alone
  head_on,  // high, balanced energy: turn to the side picked
  danger,   // something in the danger zone: brake and turn to the side picked
};

const char* to_string(MotionEnergyMode mode);

// What the controller saw and decided at its last step.
struct MotionEnergyState {
  double energy_left = 0.0;  // mean FM over the left half, [0, 1]
  double energy_right = 0.0;
  double danger_fraction = 0.0;
  bool free_path = false;
  bool free_space = false;  // the ridge's lowest point is near the horizon everywhere
  MotionEnergyMode mode = MotionEnergyMode::energy;
  double side = 0.0;  // the side picked in the head-on and danger cases: +1 right, −1 left
};

struct MotionEnergyLimits {
  double preferred_speed_mps = 1.0;
  double max_accel_mps2 = 1.0;
  double max_turn_rate = 1.0;
  double half_width_m = 0.5;  // half the width the agent needs: the danger zone's and path's
};

// Blumberg's motion-energy steering (Blumberg 1997): per-pixel energy
// FM = |fw·(I_t − I_{t−1}) + (1 − fw)·po| over each half of the image, a turn from the
// difference of the halves, the head-on case, and the ridge giving openings, a free-path test
// to the goal and the danger zone. The paper leaves the action selection to Silas's behaviour
// system; here the cases are taken in order of urgency: danger, head-on, free path to the goal,
// opening, energy. Its output is the same base::Command as the vision controller's (positive turn
// rate turns right). Keeps the previous image and every buffer between steps: no allocation per
// step once constructed.
class MotionEnergyController {
 public:
  MotionEnergyController(const base::CameraIntrinsics& intrinsics, const base::CameraMount& mount,
                         const MotionEnergyOptions& options, const MotionEnergyLimits& limits);

  // `intensity` is the image in [0, 1] and `classes` what each pixel shows, one entry per pixel
  // of the intrinsics' size, row-major. Uses the percept's goal bearing and distance (its
  // objects are not used). Throws std::invalid_argument on a size mismatch.
  base::Command step(std::span<const float> intensity, std::span<const PixelClass> classes,
                     const Percept& percept, const AgentState& agent);

  const MotionEnergyState& state() const { return state_; }
  // Per column, the row of the first non-floor pixel from the bottom, −1 when the whole
  // column is floor.
  std::span<const int> ridge() const { return ridge_; }
  std::span<const Opening> openings() const { return openings_; }

 private:
  bool free_path_to(double bearing_rad, double distance_m) const;
  void find_openings();

  base::CameraIntrinsics intrinsics_;
  base::CameraMount mount_;
  MotionEnergyOptions options_;
  MotionEnergyLimits limits_;
  double horizon_row_ = 0.0;
  // options_.corner_rise of the rows below the horizon (at least one): a corner's rise in rows.
  double corner_rise_rows_ = 0.0;
  std::vector<float> previous_;
  bool has_previous_ = false;
  std::vector<std::uint8_t> danger_zone_;  // per pixel
  int danger_zone_pixels_ = 0;
  std::vector<int> ridge_;
  std::vector<Opening> openings_;
  MotionEnergyState state_;
};

}  // namespace flowsteer::servo
