#pragma once
// Plots of an identification (write_plots), one set per channel into `directory`:
//   <channel>_residual_time.png       residual of the declared and of the final model against time
//   <channel>_residual_spectrum.png   their amplitude spectra (log scale)
//   force_loops.png                   measured force against measured displacement, with the
//                                     declared and the final model's force (a held-out window)
//   measured_tracking.png             command, measured and modelled displacement (a window)
//   measured_bode.png                 amplitude ratio (mm/mm) and phase (deg) against frequency
//                                     (Hz, log axis): measured H1 by Welch averaging against the
//                                     identified and the declared model's response, with the
//                                     coherence, over the band where it is >= 0.9 (bode.h); left
//                                     out when the record is too short or has no such band
// Every PNG has an SVG of the same figure beside it (util/plot.h).

#include <filesystem>
#include <vector>

#include "identify/fit/identify.h"

namespace rths::identify {

// Returns the files written. Throws std::runtime_error naming the file (gnuplot missing, ...).
std::vector<std::filesystem::path> write_plots(const Identification& id,
                                               const std::filesystem::path& directory);

}  // namespace rths::identify
