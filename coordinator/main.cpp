// rths-coordinator: the integrator loop of a distributed run. See coordinator/program.h.
#include "coordinator/program.h"

int main(int argc, char** argv) { return rths::coordinator::coordinator_main(argc, argv); }
