/*
 * The sandboxed reader's entry point (docs/security.md, "The reader
 * sandbox"): what the volvis-reader program runs. vv_volume_load starts
 * that program for each file a third-party parser reads (Teem, nifti_clib,
 * libtiff, GDCM), hands it the request on descriptor 3 and maps the voxels
 * it sends back; a program of one's own that embeds the library and ships
 * its own reader calls this from its main and points VOLVIS_READER at it.
 */
#ifndef VOLVIS_SYS_SANDBOX_H
#define VOLVIS_SYS_SANDBOX_H

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Reads the request from descriptor 3, locks the process down (Landlock:
 * read access beneath the input's folder only; seccomp: no sockets, no
 * execve, no new processes, read-only opens, no executable memory; no core
 * file; address-space and CPU-time limits from the request), reads the
 * file, sends the voxels back in a sealed memfd or the error trace as text,
 * and ends the process with _exit(0). Returns (2) only when it was not
 * started by the library: no request on descriptor 3, or a malformed one.
 * Not thread-safe: the whole process is the reader.
 */
int vv_sandbox_reader_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif

#endif
