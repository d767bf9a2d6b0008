/* The pixel-level rules of the MAORIS contact counts (port of the helpers of
 * ../kernels/contacts.py, whose docstrings explain them): a pixel's 3x3 zones, contour pixels,
 * the partners a pixel counts, and the changes a fusion makes. Shared by contacts.c (counting
 * from scratch) and fusion.c (tracking the counts while zones fuse).
 *
 * The label images are padded and flattened: a pixel's neighbours are pixel +- 1 and
 * pixel +- width, never outside. ``zone_of`` halves the union-find paths as it goes, so the
 * calls are made in the numba code's order (and short-circuit alike): the parents it leaves
 * are then the same.
 */
#ifndef URSIM_MAORIS_CONTACT_RULES_H
#define URSIM_MAORIS_CONTACT_RULES_H

#include "common.h"

/* _neighbourhood: the zones of a pixel's 3x3 neighbourhood, row by row (index 4: the pixel). */
static inline void neighbourhood(const int32_t *labels, int32_t *parent, int64_t pixel, int64_t width, int32_t *around)
{
    int64_t up = pixel - width, down = pixel + width;
    around[0] = (int32_t)zone_of(labels[up - 1], parent);
    around[1] = (int32_t)zone_of(labels[up], parent);
    around[2] = (int32_t)zone_of(labels[up + 1], parent);
    around[3] = (int32_t)zone_of(labels[pixel - 1], parent);
    around[4] = (int32_t)zone_of(labels[pixel], parent);
    around[5] = (int32_t)zone_of(labels[pixel + 1], parent);
    around[6] = (int32_t)zone_of(labels[down - 1], parent);
    around[7] = (int32_t)zone_of(labels[down], parent);
    around[8] = (int32_t)zone_of(labels[down + 1], parent);
}

/* _raw_neighbourhood: the same before any fusion (every label its own zone). */
static inline void raw_neighbourhood(const int32_t *labels, int64_t pixel, int64_t width, int32_t *around)
{
    int64_t up = pixel - width, down = pixel + width;
    around[0] = labels[up - 1], around[1] = labels[up], around[2] = labels[up + 1];
    around[3] = labels[pixel - 1], around[4] = labels[pixel], around[5] = labels[pixel + 1];
    around[6] = labels[down - 1], around[7] = labels[down], around[8] = labels[down + 1];
}

/* _is_contour: in a zone, with a 4-neighbour in another zone (or none). */
static inline int is_contour(const int32_t *around)
{
    int32_t own = around[4];
    return own != 0 && !(around[1] == own && around[3] == own && around[5] == own && around[7] == own);
}

/* _distinct_others: append the distinct zones of ``around`` other than 0 and the pixel's own
 * to partners[n:]; returns the new length. */
static inline int64_t distinct_others(const int32_t *around, int32_t *partners, int64_t n)
{
    int32_t own = around[4];
    int64_t start = n;
    for (int k = 0; k < 9; k++) {
        int32_t other = around[k];
        if (other == 0 || other == own) {
            continue;
        }
        int repeated = 0;
        for (int64_t j = start; j < n; j++) {
            if (partners[j] == other) {
                repeated = 1;
                break;
            }
        }
        if (!repeated) {
            partners[n] = other;
            n += 1;
        }
    }
    return n;
}

/* _count: a pixel's contacts; the count (around[4], partners[i]) grows by one for i < the
 * returned n (its contour size in ``total`` counted here). */
static inline int64_t count_pixel(const int32_t *around, int32_t *partners, int64_t *total)
{
    if (!is_contour(around)) {
        return 0;
    }
    total[around[4]] += 1;
    return distinct_others(around, partners, 0);
}

/* _recount: the changes of a pixel's counts when zone ``here`` fuses into ``into``: the count
 * (*own_out, partners[i]) changes by signs[i] for i < the returned n (contour sizes in
 * ``total`` updated here); ``around`` is rewritten to after. */
static inline int64_t recount(int32_t *around, int64_t here, int64_t into, int32_t *partners, int64_t *signs,
                              int64_t *total, int64_t *own_out)
{
    int64_t own = around[4];
    int was_contour = is_contour(around);
    int64_t n = 0;
    *own_out = own;
    if (own == here) {
        /* The pixel moves to `into` with its contour status and contacts as after. */
        for (int k = 0; k < 9; k++) {
            if (around[k] == here) {
                around[k] = (int32_t)into;
            }
        }
        if (!is_contour(around)) {
            return 0;
        }
        own = into;
        *own_out = own;
        total[own] += 1;
        n = distinct_others(around, partners, 0);
        for (int64_t i = 0; i < n; i++) {
            signs[i] = 1;
        }
    } else if (own == into) {
        if (!was_contour) {
            return 0;
        }
        int had_here = 0;
        for (int k = 0; k < 9; k++) {
            if (around[k] == here) {
                had_here = 1;
                around[k] = (int32_t)into;
            }
        }
        if (had_here && !is_contour(around)) {
            /* No longer a contour pixel: it leaves every count of `into`. */
            total[own] -= 1;
            n = distinct_others(around, partners, 0);
            for (int64_t i = 0; i < n; i++) {
                signs[i] = -1;
            }
        }
    } else if (was_contour) {
        int had_here = 0, had_into = 0;
        for (int k = 0; k < 9; k++) {
            if (around[k] == here) {
                had_here = 1;
            } else if (around[k] == into) {
                had_into = 1;
            }
        }
        if (had_here && !had_into) {
            partners[0] = (int32_t)into;
            signs[0] = 1;
            n = 1;
        }
    }
    return n;
}

/* _same_labels_around: all 8 neighbours carry the pixel's own label. */
static inline int same_labels_around(const int32_t *labels, int64_t pixel, int64_t width)
{
    int32_t raw = labels[pixel];
    int64_t up = pixel - width, down = pixel + width;
    return labels[up - 1] == raw && labels[up] == raw && labels[up + 1] == raw && labels[pixel - 1] == raw
           && labels[pixel + 1] == raw && labels[down - 1] == raw && labels[down] == raw && labels[down + 1] == raw;
}

/* _is_inner: all 8 neighbours are in zone ``own``. */
static inline int is_inner(const int32_t *labels, int32_t *parent, int64_t pixel, int64_t width, int64_t own)
{
    if (same_labels_around(labels, pixel, width)) {
        return zone_of(labels[pixel], parent) == own;
    }
    int64_t up = pixel - width, down = pixel + width;
    return zone_of(labels[pixel], parent) == own && zone_of(labels[up - 1], parent) == own
           && zone_of(labels[up], parent) == own && zone_of(labels[up + 1], parent) == own
           && zone_of(labels[pixel - 1], parent) == own && zone_of(labels[pixel + 1], parent) == own
           && zone_of(labels[down - 1], parent) == own && zone_of(labels[down], parent) == own
           && zone_of(labels[down + 1], parent) == own;
}

#endif
