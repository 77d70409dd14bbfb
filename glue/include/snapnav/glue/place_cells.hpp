#pragma once
// Place cells on the bus, in config files and on disk (library snapnav_glue_places): the INI
// sections of the place view, the localizer and the vocabulary; the place-cell memory file;
// Localization -> place_cell_match_t and pose_t.

#include <cstdint>
#include <iosfwd>
#include <stdexcept>
#include <string>

#include "snapnav/glue/ini.hpp"
#include "snapnav/nav/places/place_cells.hpp"
#include "snapnav/place_cell_match_t.hpp"
#include "snapnav/pose_t.hpp"

namespace snapnav::glue {

// The estimator and frame of the poses the place cells publish.
inline constexpr char kPlaceCellsEstimator[] = "place_cells";
inline constexpr char kPlaceCellsFrame[] = "map";

// [landmarks] method (sift | surf), equalize_histogram; [vline], [sift], [surf] (see
// ReadLandmarkExtractor) and [place_view] keep_vlines, vline_window_px (the R-HOG window of the
// lines the vline measure uses; the other [vline] keys are shared), window_px, window_scale,
// signature_width_px, signature_height_px. Every key required; bad values are ConfigError.
nav::PlaceViewOptions ReadPlaceViewOptions(const IniFile& ini);
// [matching] ratio, mutual, relaxed_second_best, max_distance, max_x_displacement_px;
// [measure] measure (bearing | count | vline), refinement (smallest | ransac), keep_fraction,
// keep_min, ransac_threshold_deg, ransac_iterations, ransac_seed, window_min_ncc, min_matches,
// templates, image_difference_weight; [distance_filter] enabled, radius_m, weight, gate_m;
// [localizer] estimate (nearest | interpolated), interpolate_k, interpolate_power, candidates,
// near_candidates, exhaustive_below, min_position_sigma_m.
nav::LocalizerOptions ReadLocalizerOptions(const IniFile& ini);
// [vocabulary] branching, depth, max_training, kmeans_iterations, seed.
nav::VocabularyOptions ReadVocabularyOptions(const IniFile& ini);

// The sections the readers above read back (header lines included).
void PrintPlaceViewOptions(std::ostream& out, const nav::PlaceViewOptions& options);
void PrintLocalizerOptions(std::ostream& out, const nav::LocalizerOptions& options);
void PrintVocabularyOptions(std::ostream& out, const nav::VocabularyOptions& options);

// A place-cell memory file that cannot be read or written.
class PlaceMemoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The memory in `path` (PlaceCellMemory::Serialize's format). Throws PlaceMemoryError naming the
// file: missing or unreadable ("cannot open"), or not a memory of this format (truncated, foreign
// magic, unsupported version ...: Parse's reason with the byte offset).
nav::PlaceCellMemory LoadPlaceMemory(const std::string& path, const nav::VocabularyOptions& vocabulary = {});
// Writes the memory to `path` atomically: a temporary file in the same folder, flushed to disk,
// then renamed over `path` (a crash leaves the old file or the new one, never half of one).
// Throws PlaceMemoryError naming the file.
void SavePlaceMemory(const nav::PlaceCellMemory& memory, const std::string& path);

// The match of a localization: the best cell's id and the pose it was recorded at (`cell` is the
// memory's cell loc.cell), the measure's distance to it, its combined score, the cells compared.
// Throws std::invalid_argument when `cell` is not loc's best cell.
place_cell_match_t ToPlaceCellMatchMsg(int64_t utime, const nav::Localization& loc, const nav::PlaceCell& cell,
                                       nav::PlaceMeasure measure);
// No cell matched: cell_id -1, zero distance, score and position.
place_cell_match_t NoPlaceCellMatchMsg(int64_t utime, nav::PlaceMeasure measure, int candidates);
// The localization's pose estimate (estimator "place_cells", frame "map", covariance row-major).
pose_t ToPlaceCellPoseMsg(int64_t utime, const nav::Localization& loc);

}  // namespace snapnav::glue
