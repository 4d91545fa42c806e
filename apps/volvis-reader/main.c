/*
 * volvis-reader: reads one volume file through a third-party parser inside
 * the sandbox and hands the voxels back to the process that started it
 * (src/io/sandbox.c; docs/security.md, "The reader sandbox"). Started by
 * vv_volume_load with its request on descriptor 3; run by hand it says so
 * and exits 2.
 */
#include "volvis/sys/sandbox.h"

int
main(int argc, char **argv) {
    return vv_sandbox_reader_main(argc, argv);
}
