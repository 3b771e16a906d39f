#pragma once
// What every subcommand shares, one header per job (this one names them all):
//   config_kind.h    loading a config of the expected kind, naming the kind a mismatched file is
//   console.h        progress on stderr, warnings
//   flags.h          time and range-checked flag values, the shared option groups
//   suggest.h        "did you mean" for unknown subcommands and flags
//   study_outputs.h  a study run's outputs and exit status

#include "cli/config_kind.h"
#include "cli/console.h"
#include "cli/flags.h"
#include "cli/study_outputs.h"
#include "cli/suggest.h"
