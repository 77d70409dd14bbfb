#pragma once
// Landmark sets on the bus and in config files (library snapnav_glue_landmarks): conversions
// between nav::LandmarkSet and landmark_set_t, and the INI sections of the extractors, the
// matching and the landmark ALV, shared by the landmarks and homing processes and the evaluation.

#include <ostream>
#include <string>

#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/landmark_set_t.hpp"
#include "snapnav/nav/landmarks/landmark_extractor.hpp"
#include "snapnav/nav/landmarks/landmarks.hpp"
#include "snapnav/nav/homing/omni_geometry.hpp"

namespace snapnav::glue {

// The message of `set` (bearings from `panorama`'s columns). Throws std::invalid_argument when
// the set does not come from a panorama of that size.
landmark_set_t LandmarkSetToMsg(const nav::LandmarkSet& set, const nav::PanoramaModel& panorama, int64_t utime,
                                const std::string& sensor_name);
// The landmark set of a message, columns from its bearings with `panorama`'s geometry. Throws
// std::invalid_argument naming what is wrong: an unknown method, a panorama size other than the
// model's, negative counts, non-finite values.
nav::LandmarkSet LandmarkSetFromMsg(const landmark_set_t& msg, const nav::PanoramaModel& panorama);

// [landmarks] method, equalize_histogram; [vline], [sift], [surf]: every key required.
nav::LandmarkExtractorConfig ReadLandmarkExtractor(const IniFile& ini);
// The extractors' sections as ReadLandmarkExtractor reads them: [vline], [sift], [surf] (the
// [landmarks] keys: PrintLandmarkExtractorKeys, inside each process's own [landmarks]).
void PrintLandmarkExtractorSections(std::ostream& out, const nav::LandmarkExtractorConfig& config);
// The [landmarks] keys ReadLandmarkExtractor reads (method, equalize_histogram), one "key = value"
// line each, no section header (a process's [landmarks] may have keys of its own).
void PrintLandmarkExtractorKeys(std::ostream& out, const nav::LandmarkExtractorConfig& config);
// The keys of [matching] and [vline_matching] (ratio, mutual, ...), declared once: placecells and
// homing read and print them through this table.
const OptionTable<nav::MatchOptions>& MatchOptionTable();
// [matching] (SIFT and SURF) or [vline_matching] (vertical lines), and [landmark_alv]; the
// matching section of `method` is read, the other one is only checked for its keys.
nav::LandmarkHomingConfig ReadLandmarkHoming(const IniFile& ini, nav::LandmarkMethod method);
// The [landmark_alv] section as ReadLandmarkHoming reads it (header line included).
void PrintLandmarkAlv(std::ostream& out, const nav::LandmarkHomingConfig& config);

}  // namespace snapnav::glue
