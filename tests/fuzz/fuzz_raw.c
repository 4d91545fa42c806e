/*
 * libFuzzer harness: raw volumes and their descriptions. The first line of
 * the input is a --raw description as the CLI parses it
 * (cli_parse_raw, apps/volvis/options.c: "WxHxD:TYPE[:be|le][:SXxSYxSZ]
 * [:skip=N]"), the rest the file read with vv_volume_load (src/io/volume/raw.c).
 */
#include "cli.h"
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const uint8_t *h, *d;
    size_t nh, nd;
    fuzz_split(data, size, "\n", &h, &nh, &d, &nd);
    if (nh > 256)
        return 0;
    char spec[257];
    memcpy(spec, h, nh);
    spec[nh] = '\0';
    if (strlen(spec) != nh)
        return 0; /* a NUL inside: not something a command line can hold */
    vv_load_options o;
    vv_load_options_init(&o);
    o.format = VV_FORMAT_RAW;
    o.has_raw = 1;
    if (cli_parse_raw(NULL, "raw", spec, &o.raw) != 0)
        return 0;
    vv_volume *v = NULL;
    if (vv_volume_load(&v, fuzz_write("in.raw", d, nd), &o) == VV_OK)
        fuzz_check_volume(v);
    return 0;
}
