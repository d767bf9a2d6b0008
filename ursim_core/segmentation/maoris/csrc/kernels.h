/* The kernels called from Python (compiled.ENTRY_KERNELS), one per numba kernel of ../kernels
 * with the same name, arguments (kernels/signatures.py) and results. Each kernel is a
 * METH_FASTCALL function; module.c lists them.
 */
#ifndef URSIM_MAORIS_KERNELS_H
#define URSIM_MAORIS_KERNELS_H

#include "common.h"

#define KERNEL(name) PyObject *kernel_##name(PyObject *self, PyObject *const *args, Py_ssize_t nargs)

/* discs.c */
KERNEL(centre_rectangles);
KERNEL(paint_discs);
/* distance.c */
KERNEL(distance_transform);
/* values.c */
KERNEL(lookup_bytes);
/* flat_zones.c, relabelling.c */
KERNEL(label_flat_zones);
KERNEL(label_radii_zones_counted);
KERNEL(zone_values_and_sizes);
KERNEL(first_pixels);
KERNEL(resolve_parents);
KERNEL(relabel);
/* adjacency.c */
KERNEL(build_adjacency);
KERNEL(adjacency_entries);
KERNEL(_link_entries);
KERNEL(remove_small_zones);
KERNEL(compact_graph);
KERNEL(expand_graph);
/* contacts.c */
KERNEL(_compact_labels);
KERNEL(count_contacts);
KERNEL(join_counts);
KERNEL(group_candidates);
KERNEL(contact_table);
/* fusion.c */
KERNEL(merge_ripples);
KERNEL(remove_doors);
/* flooding.c */
KERNEL(flood_levels);
KERNEL(clearance_levels);

#endif
