#pragma once
// RatSLAM (Milford and Wyeth 2008, 2010), as OpenRatSLAM implements it (Ball, Heath, Wiles, Wyeth,
// Corke, Milford 2013): three parts with a plain event API, and a facade that wires them as
// OpenRatSLAM's three nodes are wired.
//
//   LocalViewCells    views -> view templates. A grey panorama is cropped, averaged into a small
//                     template (template_y_size x template_x_size; 1 row: the scanline intensity
//                     profile), optionally normalised and patch normalised, and compared with every
//                     stored template by the mean absolute difference at the best column shift
//                     (on a panorama the shift spans the whole circle). Above vt_match_threshold
//                     the view becomes a new template.
//   PoseCellNetwork   a 3D continuous attractor network over (x, y, theta) that wraps in every
//                     dimension: local excitation and inhibition with 3D Gaussian weights, global
//                     inhibition, normalisation, path integration from odometry by fractional cells,
//                     energy injected by familiar view templates at the cell where each was learnt
//                     (weakened while the same template stays active: vt_active_decay,
//                     pc_vt_restore), the best cell, and the decision to create, link or switch
//                     experiences.
//   ExperienceMap     experiences (nodes with a metric pose) joined by links that carry the odometry
//                     between them; a loop closure links the current experience to an existing one,
//                     and graph relaxation (exp_loops iterations of exp_correction) spreads the
//                     odometry error around the loop.
//
// Option names are OpenRatSLAM's config keys, with a unit suffix where the value has a unit
// (pc_cell_x_size -> pc_cell_x_size_m, image_crop_x_min -> image_crop_x_min_px). Where snapnav
// departs from OpenRatSLAM it says so below (each is a fix of an inconsistency or a generalisation
// that changes nothing in OpenRatSLAM's regime):
//   - odometry is a planar increment (dx, dy, dtheta) in the robot frame instead of (vtrans, vrot) x
//     dt: the experience map composes it exactly, the pose cells shift along atan2(dy, dx) from each
//     layer's heading (for dy = 0 that is OpenRatSLAM's forward/backward shift);
//   - path integration shifts by any number of cells (bilinear weights after the integer shift;
//     OpenRatSLAM's four-rectangle weights, which are the same bilinear weights, assume < 1 cell);
//   - the heading offset of the current view (vt_relative_rad) is the view's, updated with every view
//     (OpenRatSLAM keeps the one of the last injection), and a link to a familiar experience expects
//     its heading to be the current heading minus that offset (OpenRatSLAM adds it there, and
//     subtracts it everywhere else);
//   - an experience remembers the heading offset of the view it was created with, in the pose cells
//     and in the map: moving to it, comparing the best cell with it and linking to it use the heading
//     of its template, not the robot's heading at creation (OpenRatSLAM assumes the offset was 0,
//     true for a forward camera; with a panorama, experiences made while turning broke the map);
//   - a familiar view injects its energy at the cell nearest to the template's (OpenRatSLAM truncates
//     the coordinates, which puts it half a cell off on average);
//   - the templates skipped for injection ("recently created") are pc_vt_skip_recent, also when fewer
//     exist (OpenRatSLAM's unsigned arithmetic skips none until 10 exist);
//   - on a panorama the matched shift is refined between template columns (vt_shift_subcolumn), for
//     the heading offset and the difference (OpenRatSLAM: whole columns, 6 degrees for 60 columns);
//   - patch normalisation wraps around the columns of a panoramic template (OpenRatSLAM clips at the
//     image edge), so a rotated panorama gives the rotated template;
//   - the first experience is at the start pose given to RatSlam (OpenRatSLAM: the origin, facing
//     exp_initial_em_deg), so the map frame is the odometry frame.
//
// Panorama convention (omni_geometry.hpp): column c looks at bearing bearing_col0 - c * 2 pi / width,
// so a robot that turns counter-clockwise by a sees its panorama move towards higher columns by
// a * width / 2 pi. relative_rad below is that turn (the current heading minus the heading at which
// the matched template was learnt).
//
// Pure algorithm: no I/O, no clock, no randomness; the same inputs give the same outputs. Buffers
// are allocated once: a step allocates only when the map grows (a new template, experience or link).

#include <cstdint>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "snapnav/nav/pose2.hpp"

namespace snapnav::nav {

// ------------------------------------------------------------------------------- local view cells

struct LocalViewOptions {
  // The part of the panorama that makes the template [px]: columns [x_min, x_max), rows
  // [y_min, y_max); a max of -1 means the image's width or height. OpenRatSLAM: image_crop_*.
  int image_crop_x_min_px = 0;
  int image_crop_x_max_px = -1;
  int image_crop_y_min_px = 0;
  int image_crop_y_max_px = -1;
  int template_x_size = 72;  // template columns [count]; each averages (crop width / this) columns
  int template_y_size = 12;  // template rows [count]; 1: the scanline intensity profile
  // The template's columns span 360 degrees: compare at every circular shift in steps of
  // vt_step_match (OpenRatSLAM vt_panoramic = 1). Otherwise shifts -vt_shift_match..+vt_shift_match
  // over the template's middle columns (the original RatSLAM's scanline matching).
  bool vt_panoramic = true;
  int vt_shift_match = 4;   // largest shift when not panoramic [template columns]
  int vt_step_match = 1;    // shift step [template columns]
  // snapnav: on a panorama, refine the matched shift between template columns (the view's columns
  // interpolated linearly, fractions of +-0.5 column in steps of 0.05 against the matched template),
  // so the view's heading offset is not rounded to whole columns (360 / template_x_size degrees).
  // false: whole columns (OpenRatSLAM).
  bool vt_shift_subcolumn = true;
  // A view matches its best template when their mean absolute difference is at most this
  // [intensity, 0-1]; otherwise it becomes a new template.
  double vt_match_threshold = 0.04;
  double vt_normalisation = 0;  // > 0: scale the template to this mean, clipped to [0, 1] [intensity]; 0: off
  int vt_patch_normalise = 2;   // > 0: patch normalisation over (2n+1)^2 template cells [cells]; 0: off
  double vt_min_patch_normalisation_std = 0;  // flatter patches become 0.5 [intensity]
  void Validate() const;  // throws std::invalid_argument
};

// What one view did.
struct ViewMatch {
  int template_id = -1;        // the matched or new template
  bool new_template = false;   // the view became a new template
  // Mean absolute difference to the most similar template at the best shift (refined to fractions
  // of a column with vt_shift_subcolumn) [intensity, 0-1]; nullopt when no template was compared
  // (none yet, or every one's mean differs by more than the threshold).
  std::optional<double> difference;
  int shift_columns = 0;       // template columns the view is shifted against the template (0 if new)
  double shift_fraction = 0;   // with vt_shift_subcolumn: the refinement of that shift, -0.5..0.5 [columns]
  double relative_rad = 0;     // heading now minus heading when the template was learnt [rad]
};

class LocalViewCells {
 public:
  explicit LocalViewCells(const LocalViewOptions& options);  // throws std::invalid_argument

  // Compares the view with every template; a view that matches none becomes a new one.
  // `gray`: CV_8UC1, large enough for the crop and the template. Throws std::invalid_argument
  // otherwise.
  // `mask` (image_mask.hpp: CV_8UC1 of the image's size, 0 = the robot's own parts; empty: none):
  // a template cell averages the usable pixels of its block only; a block without any takes the
  // value interpolated from its row's neighbouring cells.
  ViewMatch OnImage(const cv::Mat& gray, const cv::Mat& mask = cv::Mat());
  // The template `gray` makes, row-major template_y_size x template_x_size, values in [0, 1].
  std::vector<float> MakeTemplate(const cv::Mat& gray, const cv::Mat& mask = cv::Mat());

  const LocalViewOptions& options() const { return options_; }
  int size() const { return static_cast<int>(templates_.size()); }
  const std::vector<float>& template_data(int id) const { return templates_.at(static_cast<size_t>(id)).data; }
  int current() const { return current_; }  // -1 before the first view

 private:
  struct Template {
    std::vector<float> data;
    double mean = 0;
  };
  void ConvertView(const cv::Mat& gray, const cv::Mat& mask);  // -> view_, view_mean_
  // Best template for view_: (id, summed difference, shift); id -1 when none was compared.
  void Compare(int* best_id, double* best_sum, int* best_shift) const;
  // The summed difference of view_ against template `id` at the fractional circular offset
  // `offset` (view column c against template column c + offset; no early stop).
  double Difference(int id, double offset) const;

  LocalViewOptions options_;
  std::vector<Template> templates_;
  std::vector<float> view_;     // the current view's template
  std::vector<float> doubled_;  // view_ with each row repeated twice (circular shifts as slices)
  std::vector<float> patch_copy_;
  double view_mean_ = 0;
  int current_ = -1;
};

// --------------------------------------------------------------------------- pose-cell network

struct PoseCellOptions {
  int pc_dim_xy = 21;               // cells along x and y [count]
  int pc_dim_th = 36;               // cells over 360 degrees of heading [count]
  int pc_w_e_dim = 7;               // local excitation: weight cube side [cells, odd]
  double pc_w_e_var = 1;            // ... its Gaussian's spread (OpenRatSLAM's "var" is a std. dev.) [cells]
  int pc_w_i_dim = 5;               // local inhibition: weight cube side [cells, odd]
  double pc_w_i_var = 2;            // ... its Gaussian's spread [cells]
  double pc_global_inhib = 0.00002; // subtracted from every cell each step, floor 0 [activity]
  double pc_cell_x_size_m = 0.5;    // size of one pose cell in x and y [m]
  int pc_cells_to_avg = 3;          // the best estimate averages +- this many cells around the maximum [cells]
  double pc_vt_inject_energy = 0.015; // energy a familiar view injects: pc_vt_inject_energy/30 * (30 - e^(1.2 decay)) [activity]
  double vt_active_decay = 1.0;     // decay added each view the template stays active, and its floor [1]
  double pc_vt_restore = 0.05;      // decay removed from every template each view [1]
  int pc_vt_skip_recent = 10;       // the newest templates inject nothing (OpenRatSLAM: 10, fixed) [count]
  // A new experience when the best cell moved this far from the current experience's cell,
  // or the view changed and no experience of the view is this close [cells].
  double exp_delta_pc_threshold = 2.0;
  // snapnav: the pose cells step once this much odometry time has accumulated, with the increments
  // composed (0: on every odometry message, as OpenRatSLAM). A step shifts the packet by a fraction
  // of a cell and the attractor pulls part of it back, so a fast odometry source (50 Hz, millimetres
  // per message) makes the packet lag its motion (about 25 % at 1 cm per step and 0.5 m cells);
  // stepping less often shortens the lag but makes each injection count more [s].
  double pc_update_interval_s = 0;
  void Validate() const;  // throws std::invalid_argument
};

// The activity packet's summary.
struct PoseCellPeak {
  double x = 0, y = 0, th = 0;  // best estimate (circular mean around the maximum) [cells]
  double max_activity = 0;      // the most active cell's activity (the network sums to 1) [activity]
  int active_cells = 0;         // cells with activity > 0 [count]
};

// What the pose cells ask the experience map to do after an odometry step that follows a view
// (OpenRatSLAM's PosecellAction).
struct PoseCellAction {
  // kLinkExperience: the experience map links the current experience to `experience` (unless they
  // are linked already) and moves there. (OpenRatSLAM's SET_NODE is never produced by its logic.)
  enum Kind { kNone, kCreateExperience, kLinkExperience };
  Kind kind = kNone;
  int experience = -1;      // the new experience, or the familiar one linked to or switched to
  double relative_rad = 0;  // heading offset of the current view (ViewMatch::relative_rad) [rad]
};

class PoseCellNetwork {
 public:
  // One unit of activity in the middle cell (pc_dim_xy / 2, pc_dim_xy / 2, pc_dim_th / 2).
  explicit PoseCellNetwork(const PoseCellOptions& options);  // throws std::invalid_argument

  // One odometry step (OpenRatSLAM on_odo): Iterate(), then PathIntegrate() by translation_m /
  // pc_cell_x_size_m along (each layer's heading + direction_rad) and by rotation_rad, then the
  // best estimate. Throws std::invalid_argument on a non-finite value.
  void OnOdometry(double translation_m, double direction_rad, double rotation_rad);
  // A view was matched to template `id` (id == the number of templates seen: a new template,
  // which remembers the best cell) at heading offset relative_rad. A familiar template, unless
  // among the pc_vt_skip_recent newest, injects energy at its cell, the heading moved by the
  // offset. Throws std::invalid_argument if id skips a template.
  void OnViewTemplate(int id, double relative_rad);
  // After an odometry step that follows a view: create an experience, link to or switch to a
  // familiar one (of the current template, within exp_delta_pc_threshold of the best cell), or
  // nothing. Each view gives at most one action.
  PoseCellAction GetAction();

  // The parts of a step, public for tests and the benchmark.
  void Iterate();  // local excitation, local inhibition, global inhibition, normalisation
  void PathIntegrate(double translation_cells, double direction_rad, double rotation_rad);
  void FindBest();
  void Inject(int x, int y, int th, double energy);  // cells outside the network are ignored
  void SetSingleCell(int x, int y, int th);          // all activity in one cell (then FindBest)

  const PoseCellOptions& options() const { return options_; }
  double activity(int x, int y, int th) const { return cells_[Index(x, y, th)]; }
  // Activities, index (th * pc_dim_xy + y) * pc_dim_xy + x.
  const std::vector<double>& cells() const { return cells_; }
  PoseCellPeak peak() const;
  double best_x() const { return best_x_; }
  double best_y() const { return best_y_; }
  double best_th() const { return best_th_; }
  // Heading of the best estimate in the cells' own frame [rad].
  double best_heading_rad() const;
  int templates() const { return static_cast<int>(templates_.size()); }
  int experiences() const { return static_cast<int>(experiences_.size()); }
  int current_experience() const { return current_exp_; }
  int injections() const { return injections_; }  // views that injected energy [count]

 private:
  struct ViewCell {    // OpenRatSLAM PosecellVisualTemplate
    double x, y, th;   // best cell when the template was learnt [cells]
    double decay;
    std::vector<int> experiences;
  };
  struct CellExperience {  // OpenRatSLAM PosecellExperience
    double x, y, th;
    int view_template;
    double th_offset;  // the view's heading offset when it was created [cells]
  };
  size_t Index(int x, int y, int th) const {
    return (static_cast<size_t>(th) * options_.pc_dim_xy + static_cast<size_t>(y)) * options_.pc_dim_xy +
           static_cast<size_t>(x);
  }
  void Spread(const std::vector<double>& weights, int dim, std::vector<double>* out) const;
  double DeltaPc(const CellExperience& e) const;
  void CreateExperience();

  PoseCellOptions options_;
  std::vector<double> cells_, scratch_;
  std::vector<double> excite_weights_, inhibit_weights_;
  std::vector<int> wrap_xy_, wrap_th_;  // index + offset -> wrapped index, for offsets -dim..2 dim
  std::vector<double> sum_x_, sum_y_, sum_th_;
  std::vector<double> layer_;           // one theta layer, for path integration
  double best_x_ = 0, best_y_ = 0, best_th_ = 0;
  std::vector<ViewCell> templates_;
  std::vector<CellExperience> experiences_;
  int current_vt_ = -1, prev_vt_ = -1;
  int current_exp_ = -1;
  double vt_delta_pc_th_ = 0;  // heading offset of the current view [cells]
  double vt_relative_rad_ = 0;
  bool odo_update_ = false, vt_update_ = false;
  int injections_ = 0;
};

// ---------------------------------------------------------------------------- experience map

struct ExperienceMapOptions {
  int exp_loops = 20;          // relaxation iterations after each action [count]
  double exp_correction = 0.5; // share of a link's disagreement corrected per iteration [0-1]
  void Validate() const;       // throws std::invalid_argument
};

struct Experience {
  Pose2 pose;                 // in the map frame [m, rad]; moves with relaxation
  int view_template = -1;     // the template it was created with
  double view_relative_rad = 0;  // that view's heading offset (ViewMatch::relative_rad) then [rad]
  std::vector<int> links_from, links_to;  // link indices
};

// What the odometry said between two experiences, in the frame of `from` (OpenRatSLAM Link).
struct ExperienceLink {
  int from = -1, to = -1;
  double d_m = 0;          // distance [m]
  double heading_rad = 0;  // direction of `to` seen from `from`, relative to from's heading [rad]
  double facing_rad = 0;   // to's heading minus from's [rad]
  double dt_s = 0;         // odometry time between them [s] (OpenRatSLAM never resets it: ours restarts per experience)
  bool loop_closure = false;  // links a familiar experience (not one just created)
};

class ExperienceMap {
 public:
  // The robot starts at `start` (map frame = odometry frame); no experience yet.
  ExperienceMap(const ExperienceMapOptions& options, const Pose2& start);  // throws std::invalid_argument

  // Accumulates an odometry increment (robot frame) since the current experience.
  void OnOdometry(const Pose2& delta, double dt_s);
  // A new experience where the robot is (the current one plus the odometry since), linked from the
  // current one; it becomes the current one. `relative_rad`: the heading offset of the current view
  // against its template. Returns its id.
  int CreateExperience(int view_template, double relative_rad = 0);
  // Links the current experience to `to` with the odometry accumulated since the current one (the
  // robot is at `to`, seeing to's template with heading offset relative_rad). False if the two are
  // already linked either way (or `to` is the current one). Throws std::out_of_range for an unknown
  // id or before the first experience.
  bool LinkTo(int to, double relative_rad, bool loop_closure);
  // The robot is at experience `id`, seeing its template with heading offset relative_rad: it faces
  // the experience's heading plus (relative_rad - the offset the experience was created with). The
  // odometry since restarts there. Throws std::out_of_range for an unknown id.
  void SetExperience(int id, double relative_rad);
  // exp_loops iterations of relaxation over every link.
  void Relax();

  const ExperienceMapOptions& options() const { return options_; }
  const std::vector<Experience>& experiences() const { return experiences_; }
  const std::vector<ExperienceLink>& links() const { return links_; }
  int current() const { return current_; }  // -1 before the first experience
  // Where the robot is: the current experience's pose plus the odometry since (the start plus the
  // odometry before the first experience) [m, rad].
  Pose2 robot_pose() const;

 private:
  ExperienceMapOptions options_;
  std::vector<Experience> experiences_;
  std::vector<ExperienceLink> links_;
  int current_ = -1;
  Pose2 origin_;           // the current experience's pose when it became current (or the start)
  double accum_x_m_ = 0, accum_y_m_ = 0;  // odometry since, map frame [m]
  double accum_facing_rad_ = 0;           // heading now, map frame [rad]
  double accum_time_s_ = 0;
};

// ------------------------------------------------------------------------------------- facade

struct RatSlamOptions {
  LocalViewOptions local_view;
  PoseCellOptions pose_cells;
  ExperienceMapOptions experience_map;
  void Validate() const;  // throws std::invalid_argument
};

struct RatSlamViewResult {
  int template_id = -1;
  bool new_template = false;
  std::optional<double> match_difference;  // ViewMatch::difference [intensity, 0-1]
  double relative_rad = 0;                 // ViewMatch::relative_rad [rad]
};

class RatSlam {
 public:
  explicit RatSlam(const RatSlamOptions& options, const Pose2& start = {});  // throws std::invalid_argument

  // An odometry increment in the robot frame of the previous step, over dt_s. Steps the experience
  // map, and the pose cells with the increments since their last step once pc_update_interval_s of
  // them have accumulated; after a pose-cell step applies their action (new experience, link,
  // switch, then relaxation). Throws std::invalid_argument on non-finite values or dt_s < 0.
  void OnOdometry(const Pose2& delta_robot_frame, double dt_s);
  // A grey panorama (CV_8UC1, columns over 360 degrees): local view match, then the pose cells.
  RatSlamViewResult OnImage(const cv::Mat& panorama_gray, const cv::Mat& mask = cv::Mat());

  // The robot's pose in the experience-map frame (which starts at `start`): the current
  // experience's pose plus the odometry since it, as OpenRatSLAM places a new experience.
  Pose2 pose() const { return map_.robot_pose(); }
  // The current experience's pose (OpenRatSLAM's published robot pose); nullopt before the first.
  std::optional<Pose2> experience_pose() const;
  const ExperienceMap& experience_map() const { return map_; }
  const PoseCellNetwork& pose_cells() const { return cells_; }
  const LocalViewCells& local_view() const { return view_; }
  const RatSlamOptions& options() const { return options_; }

  int loop_closures() const { return loop_closures_; }      // links created to familiar experiences
  int experience_switches() const { return switches_; }     // moves to a familiar experience without a new link
  int templates() const { return view_.size(); }
  PoseCellPeak pose_cell_peak() const { return cells_.peak(); }
  int64_t odometry_steps() const { return odometry_steps_; }
  int64_t images() const { return images_; }

 private:
  RatSlamOptions options_;
  LocalViewCells view_;
  PoseCellNetwork cells_;
  ExperienceMap map_;
  int loop_closures_ = 0, switches_ = 0;
  int64_t odometry_steps_ = 0, images_ = 0;
  Pose2 pc_pending_;          // odometry since the last pose-cell step
  double pc_pending_s_ = 0;   // its duration [s]
};

}  // namespace snapnav::nav
