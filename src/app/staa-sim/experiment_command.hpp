#pragma once
// `staa-sim experiment` (docs/ARCHITECTURE.md section 6): the paper's comparison (Sec. IV-B/IV-C)
// as one command. argv[0] is "experiment". Exit status: 0 on a completed experiment, 2 on bad
// input (the option and the value on stderr), 1 when a run fails.

namespace staa {

int runExperimentCommand(int argc, char** argv);

}  // namespace staa
