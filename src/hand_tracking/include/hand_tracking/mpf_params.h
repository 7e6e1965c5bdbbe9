// Parameters of the MPF hand/head tracker (thesis 5.1, 6.3). Units are SI (metres, seconds).
// Where the thesis gives a figure it is quoted; the others it leaves open, and the comment says
// how the default was chosen (the simulated rig: 8 cameras, 64x64x48 volumes of 15.6 mm voxels).
#pragma once

#include <Eigen/Core>

#include "hand_tracking/head_model.h"

namespace hand_tracking {

struct MpfParams {
  // ---- Particles (thesis 5.1 / 7.1: 400 per hand, 200 for the head) ------------------------
  int hand_particles = 400;
  int head_particles = 200;

  // ---- Observation model (thesis 5.1.3) -----------------------------------------------------
  // Head: mean skin-coloured-foreground probability in a box that encompasses the head (edge
  // lengths, m). The simulated head's skin ellipsoid is 15 x 19 x 23 cm, the face its front
  // half. A box that holds the whole head fills with skin where a hand, or both hands
  // together, fill well under half of it (the volume-size cue that tells heads from hands);
  // a smaller one (12 cm) settles on the neck and chin, which are skin too.
  Eigen::Vector3d head_box{0.18, 0.18, 0.20};
  // The head is the top of the body: its observation is multiplied by the mean non-occupancy
  // (1 - P(F), body volume) of a horizontal slab over the head box's cross-section,
  // head_crown_thickness thick, head_crown_gap above the box's top. Not in the thesis: its
  // users wore clothes that are not skin-coloured. A shirt in a skin tone (brown, beige,
  // orange) makes the chest the largest skin blob, and the head track ends there with the
  // face taken for a hand (4 of 48 generated scenarios, random-27, 28, 34, 39). Over
  // the chest, the neck and head fill the slab; over a head nothing does. The gap keeps the
  // slab clear of the real head's crown: the head particles settle on the face and neck (the
  // skin), 5 cm and more below the head's centre, and the crown with hair and the hull's halo
  // reaches 14-18 cm above the centre, i.e. up to 13 cm over the box's top (a 10 cm gap lost
  // the head in one of 48 generated scenarios). A wider gap lets the head track sink onto the
  // neck of a skin-coloured shirt (0.20 m, whole scripts: random-34's head 12.8 -> 21.3 mm;
  // docs/benchmarks.md, "MPF: the head's birth threshold"). 0 thickness = off.
  double head_crown_thickness = 0.032;  // m, two voxels of the 64x64x48 tracking volume
  double head_crown_gap = 0.13;         // m between the head box's top and the slab
  // Hand: mean skin probability in a palm-sized box (m) times the mean non-occupancy (1 - P(F)
  // from the body volume) of the box's frontal plane: a slab of frontal_plane_thickness just
  // outside the box face that points along frontal_direction, over the box's cross-section.
  // A palm is ~8 x 10 x 3 cm; 9 cm also holds a fist.
  Eigen::Vector3d hand_box{0.09, 0.09, 0.09};
  // Unit vector along +-x, +-y or +-z (boxes are axis-aligned): towards the screen. In the
  // world frame of DESIGN.md section 3 (and the simulated rig) the user sits at -y and the
  // screen stands at +y, so +y. The user's hands never pass through this plane, forearms do.
  Eigen::Vector3d frontal_direction = Eigen::Vector3d::UnitY();
  double frontal_plane_thickness = 0.016;  // m, one voxel of the 64x64x48 tracking volume
  double frontal_plane_gap = 0.0;          // m between the box face and the slab
  // Particle weight = observation^likelihood_exponent. The thesis uses the observation itself
  // (exponent 1); box means change slowly with position (a 1 cm shift of a 9 cm box changes
  // the mean by ~10 %), so raw weights barely discriminate within a particle cloud: on the
  // simulated rig the hand clouds then drift off their hands within seconds. The exponent
  // sharpens the likelihood (the annealing device of 5.2); 1 reproduces the thesis.
  double likelihood_exponent = 8.0;
  // true: boxes integrate the voxel field with fractional coverage of boundary voxels
  // (IntegralVolume::boxMeanSmooth, 64 reads per box), so the likelihood is continuous in the
  // particle position; false: voxel-centre box means (8 reads), as the thesis.
  bool smooth_boxes = true;

  // ---- Dynamics (thesis 5.1.3: head random walk; hands 1/3 each AR(1), AR(2), AR(3)) ---------
  // Process noise: standard deviation per axis of one step of reference_dt (m); steps of other
  // lengths scale it linearly (motion per frame is proportional to the frame time).
  double reference_dt = 0.04;    // s (25 fps)
  double head_noise = 0.008;     // random walk; a seated head moves < 0.2 m/s
  double hand_noise_ar1 = 0.02;  // random walk: covers ~0.5 m/s of unmodelled motion per axis
  double hand_noise_ar2 = 0.008; // constant velocity
  double hand_noise_ar3 = 0.005; // constant acceleration
  // Speed limit of a particle (m/s): keeps the AR(2)/AR(3) extrapolations of noisy particle
  // histories from running away. Reaching hands peak at ~1.5 m/s.
  double max_speed = 3.0;

  // ---- Track birth (thesis 5.1.2) -----------------------------------------------------------
  // Inactive components scatter their particles over the workspace (half uniformly, half on
  // voxels of the skin volume above search_skin_threshold, a proposal that only decides where
  // to look); the best one activates the component if its observation reaches the
  // initialisation weight and it lies at least birth_min_distance from every tracked target.
  // Observations of the simulated rig's volumes (hands: palm box; head: head box): an empty
  // workspace ~0.04 everywhere, a hand resting on the desk ~0.35, a raised hand 0.35-0.45, the
  // face seen through a palm box ~0.5 (the head distance keeps hands off it). The head is
  // ~0.55-0.65 on the default scenario but 0.3-0.45 where hair, dark skin or a coloured light
  // leave less of the head box skin: at 0.45 the head of random-10 (orange light) was never
  // found over its whole script and a hand track took its face, and four of random-25..48
  // never had a head. Long hair over the sides and back leaves the face alone skin: 0.29-0.30
  // at the true head of random-20 and random-49 (auburn long hair) and 0.29 on random-44, the
  // best spot a few cm lower 0.32-0.36; at 0.35 none of them ever had a head, and a hand track
  // took the face. 0.28 found all three and changed nothing else on 72 scenarios
  // (docs/benchmarks.md). A hand or forearm fills under a tenth of a head box.
  // The birth rule below (the head starts near the top of the body) keeps the lower threshold
  // off chests and arms; the volume-size check (no hand birth where a head would be) uses it
  // too.
  double head_init_weight = 0.28;  // observation (0..1)
  // The head track starts only within head_birth_depth (m) below the top of the body (the
  // highest level of the body volume with head_birth_top_area (m^2) occupied, body_top.h),
  // not on a skin-coloured chest whose head box outscores the head's (hair is not skin). The
  // face, where head particles settle, lies up to ~20 cm below the top of a head with hair
  // and the hull's halo, the chest 35 cm and more. Area: 17 voxels of 15.6 mm, a head's crown
  // 2 cm below its top; a raised hand's cross-section is about half of it. The crown slab above
  // keeps a track that started on the head from sliding onto such a chest. 0 depth = off.
  double head_birth_depth = 0.30;
  double head_birth_top_area = 0.004;
  double hand_init_weight = 0.25;
  double birth_min_distance = 0.15;  // m
  double birth_spread = 0.02;        // m, std of the new component's particles around the find
  // A hand track is not born, nor split off, where the straight line to a tracked hand's
  // particle mean runs through skin over at least this fraction of its length: that is the
  // same limb (skin_path.h: with bare forearms the elbow fills a palm box better than a flat
  // hand, and the second track was born there while the other hand went unseen). Two hands
  // side by side read 0.67 at 15 cm between centres, 0.44 at 20 and 0.25 at 36 cm; hands with
  // the finger tips towards each other count as one limb until the tips are about 7 cm apart,
  // as clasped hands are one target. 0 = off.
  double birth_limb_fraction = 0.7;
  double search_skin_threshold = 0.5;
  double search_skin_fraction = 0.5;

  // ---- Reconfiguration (thesis 5.1.2): k-means + merge / split / loss ------------------------
  int kmeans_max_iterations = 50;  // thesis: 50, "never reached in practice"
  // A hand keeps a cluster of its own only while its observation at the estimate reaches the
  // tracking weight (else it is lost; hysteresis: tracking < initialisation weight) and it
  // lies at least merge_distance from the means chosen before it (else it merges).
  double head_track_weight = 0.25;
  double hand_track_weight = 0.15;
  double merge_distance = 0.10;  // m
  // A merged (or any) hand cloud splits when its best particle reaches the initialisation
  // weight at least split_distance from every chosen mean (> merge_distance: hysteresis).
  double split_distance = 0.15;  // m
  // A hand closer than this to the head's mean is taken for part of the head (neck, chin,
  // face: the simulated neck is bare skin, like the thesis' users'): no hand is born there,
  // and a hand that gets there is lost (its particles settle on the head: foreign type).
  double head_hand_distance = 0.22;  // m
  // Mixture weights pi_m,t ~ pi_m,t-1 x (mean particle weight) are kept above this floor
  // (then renormalised): the product over frames would otherwise drive a component whose
  // observation is systematically lower (hands vs head) to 0 within seconds.
  double min_mixture_weight = 0.01;
  // A hand that comes back (split after a merge, or re-found after a loss while the other
  // hand stayed tracked) gets its old identity if it returns within this time (s).
  double identity_memory = 10.0;

  // ---- Workspace (DESIGN.md section 3 default user space) -----------------------------------
  Eigen::Vector3d workspace_min{-0.5, -0.5, 0.0};
  Eigen::Vector3d workspace_size{1.0, 1.0, 0.75};

  // ---- Reported position --------------------------------------------------------------------
  // true: the reported position is the centroid of the skin probability within a box around
  // the particle mean (voxels above a threshold, nearer this target's particle mean than any
  // other target's), iterated (mean shift); false: the weighted particle mean (thesis).
  // Why: the box likelihood peaks where the box holds the most skin, which is where the palm
  // is, not at the centroid of palm + fingers; the frontal-plane factor pushes it towards the
  // finger tips. The refinement measures what the target's position is defined as.
  // Hands: a 16 cm box, +-8 cm around the estimate: from the centre of an average hand's visible
  // skin (about 8 cm from the wrist) it reaches the wrist and most of the fingers. The 20 cm box
  // used until 2026-12-07 also took in the hull's skin halo around a bare forearm and nearby
  // skin blobs, and the mean shift followed them: on 72 generated scenarios (100 frames) the
  // hands' medians went 30.7 / 59.3 / 35.3 -> 26.0 / 54.6 / 35.2 mm (12 scenarios better by
  // more than 3 mm, 1 worse), on 24 others not used to choose it 67.6 -> 60.6 mm (5 / 2);
  // docs/benchmarks.md, 2026-12-07. Voxels above 0.6
  // count (the hull at the hand meshes' iso level, thesis 6.5): lower thresholds let in the
  // fringe of voxels that are skin in only some views, higher ones keep only the hull's thick
  // core (palm, wrist) and lose the fingers. On the simulated rig (reach_targets; 'all'):
  // 0.9 -> 9.4 / 10.6 mm (12.1 / 17.4), 0.75 -> 6.9 / 9.2, 0.6 -> 6.1 / 8.0 (7.2 / 8.9),
  // 0.4 -> 6.4 / 9.7 mm (left / right hand means).
  bool refine_hand_centroid = true;
  Eigen::Vector3d hand_centroid_box{0.16, 0.16, 0.16};
  double hand_centroid_threshold = 0.6;
  // Distal cut of that centroid (m, 0 = off; distal_centroid.h): with short or rolled sleeves
  // the forearm is skin as well, and the box's centroid slid 9-18 cm down the arm on generated
  // scenarios. When the skin in the larger hand_arm_box is elongated and longer than this plus
  // the hull's smear, the centroid of the voxels within this length of its hand end
  // (hand_end_by_body) is reported instead (needs a tracked head). A hand is 16-21 cm from
  // wrist to finger tips; 0.17 m keeps an open hand whole and drops most of the forearm.
  double hand_distal_length = 0.17;
  // Edge (m) of the box, centred like the one above, in which the distal cut looks for an arm:
  // it must hold more than a hand with the hull's smear (0.17 + 0.05 m) along a diagonal arm.
  double hand_arm_box = 0.32;
  // Which end of that arm is the hand: true: the end with less body that is not skin around it
  // (the sleeve goes on from the elbow; distal_centroid.h), the head's rule where the two ends
  // differ by less than kForeignMargin (0.1); false: the end away from the head only (the arm
  // walk below has its own rules, the hand in front of the elbow first). A
  // forearm raised to wave or bent towards the body has its hand nearer the head than its
  // elbow: the head's rule reported the elbow.
  bool hand_end_by_body = true;
  // Where that box sees an arm but its answer lies at the arm's root end (m, 0 = off;
  // arm_geodesic.h): the particles sit on the elbow of a stretched or raised bare arm, and the
  // box sees neither end. The skin is then walked up to this far from them, the blob's two
  // ends found along it, and the hand's centroid (hand_distal_length from the hand's end)
  // reported. 0.6 m: a short sleeve to the finger tips. On 72 generated scenarios (100 person
  // frames, mean hand error per scenario): four with bare arms 117-158 mm -> 8-76 mm, three
  // 4-7 mm better, three 6-7 mm worse (docs/benchmarks.md, "MPF: the hand's end along the
  // skin"). Not on a target that holds both hands (after a merge).
  double hand_arm_walk = 0.6;
  // Head: a head-sized box and every voxel (the hull's fringe around the face reaches into the
  // hair and balances the face towards the head's centre). On the simulated rig it leaves the
  // mean error as it is and halves the worst case (the particle mean follows the face as the
  // head turns).
  bool refine_head_centroid = true;
  Eigen::Vector3d head_centroid_box{0.20, 0.20, 0.20};
  double head_centroid_threshold = 0.0;
  int centroid_iterations = 3;
  // Head model (head_model.h): report the head's centre fitted in the body volume around the
  // face estimate above (a fit that fails reports the face estimate). false: the face estimate.
  bool head_model = true;
  HeadModelParams head_fit;

  // OpenMP threads for the particle weights (0 = OpenMP default). A second thread gains little
  // (see docs/benchmarks.md (bench_mpf)): the serial prediction and the integral volumes
  // dominate, and in a nodelet manager a second team would compete with the reconstruction's.
  int threads = 1;

  // Throws std::invalid_argument naming the field.
  void validate() const;
};

}  // namespace hand_tracking
