// Segment inertia parameters of de Leva (1996), "Adjustments to Zatsiorsky-Seluyanov's segment
// inertia parameters", J. Biomechanics 29(9), Table 4, male subjects (reference stature 1741 mm).
// Lengths in mm at the reference stature; CoM position and radii of gyration as fractions of the
// segment length (CoM measured from the proximal end point named in the comment).
#pragma once

namespace sparsebody::character::de_leva {

struct Segment {
  double mass_fraction;  // of total body mass
  double length_mm;      // at stature 1741 mm
  double com;            // fraction of length from the proximal point
  double r_sag, r_trans, r_long;  // radii of gyration / length: sagittal, transverse, longitudinal
};

constexpr double kStatureMm = 1741.0;
constexpr Segment kHead{0.0694, 242.9, 0.5976, 0.362, 0.376, 0.312};          // from vertex to C7
constexpr Segment kUpperTrunk{0.1596, 242.1, 0.5066, 0.505, 0.320, 0.465};    // from C7 to xiphoid
constexpr Segment kMiddleTrunk{0.1633, 215.5, 0.4502, 0.482, 0.383, 0.468};   // xiphoid to omphalion
constexpr Segment kLowerTrunk{0.1117, 145.7, 0.6115, 0.615, 0.551, 0.587};    // omphalion to mid-hip
constexpr Segment kUpperArm{0.0271, 281.7, 0.5772, 0.285, 0.269, 0.158};      // shoulder to elbow
constexpr Segment kForearm{0.0162, 268.9, 0.4574, 0.276, 0.265, 0.121};       // elbow to wrist
constexpr Segment kHand{0.0061, 86.2, 0.7900, 0.628, 0.513, 0.401};           // wrist to 3rd metacarpal
constexpr Segment kThigh{0.1416, 422.2, 0.4095, 0.329, 0.329, 0.149};         // hip to knee
constexpr Segment kShank{0.0433, 434.0, 0.4459, 0.255, 0.249, 0.103};         // knee to ankle
constexpr Segment kFoot{0.0137, 258.1, 0.4415, 0.257, 0.245, 0.124};          // heel to toe tip

}  // namespace sparsebody::character::de_leva
