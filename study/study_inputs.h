#pragma once
// A study that carries its inputs, so that a run record can be viewed, identified, exported and
// re-run anywhere, with nothing beside it.
//
//   with_embedded_inputs(prepared) -> config::Study
//     prepared.config with every file it reads replaced by what was read:
//       motion      motion.embedded = the record as run (prepared.motion: at the run's dt, scaled
//                   and cut, m/s^2) with the file's SHA-256; path kept, made absolute
//       matrices    structure.matrices.{mass,stiffness,damping,influence}: a file read sparse
//                   (.mtx coordinate, a sparse .mat variable) becomes inline `sparse` triplets
//                   (study/sparse_triplets.h: O(nnz), the lower triangle of a symmetric one),
//                   any other file (.csv, .mtx array, a full .mat variable) inline rows + values
//                   (row-major); exactly the doubles read
//       traces      every delay stage's trace (cases, and nodes' receive / send stages) gets its
//                   time and delay samples; path kept, made absolute
//     Loading the result needs no file: load_motion, make_structure and make_delay_stage take the
//     embedded forms first. Throws std::invalid_argument as the loaders do (a file gone since).
//   inputs_source(study, base_dir) -> text
//     Says where a study loaded from a record takes its inputs: "embedded in the record", or, for
//     a record written before records carried them, the files it falls back to (absolute).

#include <filesystem>
#include <string>

#include "study/study.h"

namespace rths::study {

config::Study with_embedded_inputs(const PreparedStudy& prepared);

std::string inputs_source(const config::Study& study, const std::filesystem::path& base_dir);

}  // namespace rths::study
