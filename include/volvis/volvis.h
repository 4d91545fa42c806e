/*
 * VolVis: the whole public API. Each component has its own header; this one
 * includes them all. See docs/architecture.md.
 */
#ifndef VOLVIS_VOLVIS_H
#define VOLVIS_VOLVIS_H

#include "animate.h"
#include "bricks.h"
#include "compress.h"
#include "core.h"
#include "filter.h"
#include "grid.h"
#include "image.h"
#include "input.h"
#include "io.h"
#include "math.h"
#include "measure.h"
#include "mesh.h"
#include "model.h"
#include "modeling.h"
#include "navigator.h"
#include "parallel.h"
#include "radiosity.h"
#include "raster.h"
#include "render.h"
#include "scene.h"
#include "slice.h"
#include "source.h"
#include "surface.h"
#include "video.h"
#include "volume.h"

#endif
