/*
 * Helpers shared by the files of src/manipulate (not installed).
 */
#ifndef VOLVIS_ANIM_INTERNAL_H
#define VOLVIS_ANIM_INTERNAL_H

#include "volvis/animate.h"

/** Parses a property path into its target and value kind. Errors: VV_ERR_INVALID. */
vv_status vv_anim_parse_property(const char *prop, vv_anim_target *t, vv_anim_kind *kind);

/** Number of doubles a key value of @p k has (0 for a transfer function). */
int vv_anim_kind_components(vv_anim_kind k);

/** 1 when the track's values are angles (radians inside, degrees in files): view.fov. */
int vv_anim_property_is_angle(const vv_anim_track *t);

/** Checks one track; *bad_key is the offending key or -1. Errors: VV_ERR_INVALID. */
vv_status vv_anim_track_validate(const vv_anim_track *t, int *bad_key);

/** Checks one sequence's fields. Errors: VV_ERR_INVALID. */
vv_status vv_anim_sequence_check(const vv_anim_sequence *q);

/**
 * Applies the animation at @p time to @p world in place: @p world must hold
 * the base state (a vv_world_clone of the World the animation was made for),
 * as the sequences are relative to it. Errors: VV_ERR_INVALID (a target is
 * missing, see vv_animation_check_world), VV_ERR_NOMEM.
 */
vv_status vv_animation_apply(const vv_animation *a, vv_world *world, double time);

#endif
