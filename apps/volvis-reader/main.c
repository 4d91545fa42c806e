/*
 * volvis-reader: reads one file through a third-party parser inside the
 * reader sandbox and hands the result back to the process that started it
 * (src/sandbox; docs/security.md, "The reader sandbox"). Started by the
 * library with its request on descriptor 3; run by hand it says so and
 * exits 2.
 */
#include "volvis/sys/format.h"

int
main(int argc, char **argv) {
    return vv_format_reader_main(argc, argv);
}
