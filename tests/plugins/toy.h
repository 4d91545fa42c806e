/* A toy format row and a toy rendering method, each in one file
 * (toy_format.c, toy_renderer.c), for test_toy.c: what a plug-in adds. */
#ifndef VV_TEST_TOY_H
#define VV_TEST_TOY_H

#include "volvis/sys/format.h"
#include "volvis/sys/renderer.h"

/** The .toy format's row (toy_format.c). */
extern const vv_format_record toy_format;
/** The "toymip" rendering method (toy_renderer.c). */
extern const vv_renderer_ops toy_renderer;

#endif
