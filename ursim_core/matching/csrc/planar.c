/* The planar matcher's seed-and-expand loop in C (module ``_matching_kernels``, see module.c).
 *
 * A port of ursim_core/matching/planar.py's planar_match for its common case (no constraints,
 * no alternatives kept), which stays the reference: the same seeds in the same order, the same
 * edit-distance alignments with the same backtrace ties (edit_distance.py), the same FIFO
 * expansion between locks (arcs.py), the same cost and the same earliest-wins rule. The pair
 * costs are summed in pair order in doubles, as Python's sum does on 3.11, so the costs are
 * the same floats. Tests compare both on random graphs with many ties, on graphs with hubs of
 * hundreds of neighbours, on the KTH pairs and on generated buildings.
 *
 * Why C: a turned KTH sketch is matched about 740 times (eight segmentations, the finalist
 * orientations, the m grid, the refits), and Python spent 58 of the 130 ms of such a match in
 * this loop. Graphs of any size: alignments of up to ``table_cells`` cells fill a table here,
 * longer ones (a building's corridor against the other map's, 4250 neighbours each) run
 * bit-parallel (bitalign.c); the consumed seeds are one bit a (sketch, metric) pair (2.3 MB for
 * two 4250-region maps), and a lock's position in a long metric order is looked up, not searched.
 */
#include "kernels.h"

#include <stdlib.h>
#include <string.h>


/* Levenshtein table of ``a`` (rows) against ``b`` (columns); returns the distance. */
static int32_t fill_table(const Graphs *g, const int32_t *a, int32_t rows, const int32_t *b, int32_t cols)
{
    int32_t *t = g->table;
    int32_t width = cols + 1;
    for (int32_t j = 0; j <= cols; j++) {
        t[j] = j;
    }
    for (int32_t i = 1; i <= rows; i++) {
        const uint8_t *same_row = g->same + (int64_t)a[i - 1] * g->n2;
        int32_t *above = t + (int64_t)(i - 1) * width, *here = t + (int64_t)i * width;
        here[0] = i;
        int32_t left = i;
        for (int32_t j = 1; j <= cols; j++) {
            int32_t value = above[j - 1] + (same_row[b[j - 1]] ? 0 : 1);
            if (above[j] + 1 < value) {
                value = above[j] + 1;
            }
            if (left + 1 < value) {
                value = left + 1;
            }
            here[j] = value;
            left = value;
        }
    }
    return t[(int64_t)rows * width + cols];
}

/* aligned_index_pairs: the diagonal steps of the backtrace of the filled table, first to last.
 * Writes pairs (a_k, b_k) to ``out`` and returns their number. */
static int32_t backtrace_pairs(const Graphs *g, const int32_t *a, int32_t rows, const int32_t *b, int32_t cols,
                               int32_t *out)
{
    const int32_t *t = g->table;
    int32_t width = cols + 1, count = 0;
    int32_t i = rows, j = cols;
    while (i > 0 && j > 0) {
        int32_t diagonal = t[(int64_t)(i - 1) * width + j - 1], up = t[(int64_t)(i - 1) * width + j],
                left = t[(int64_t)i * width + j - 1];
        if (diagonal <= up && diagonal <= left) {
            i--;
            j--;
            out[2 * count] = a[i];
            out[2 * count + 1] = b[j];
            count++;
        } else if (left <= up) {
            j--;
        } else {
            i--;
        }
    }
    reverse_pairs(out, count); /* first elements first */
    return count;
}

static int32_t aligned_index_pairs(const Graphs *g, const int32_t *a, int32_t rows, const int32_t *b, int32_t cols,
                                   int32_t *out)
{
    if (rows == 0 || cols == 0) {
        return 0;
    }
    if (rows == 1 && cols == 1) {
        out[0] = a[0];
        out[1] = b[0];
        return 1;
    }
    fill_table(g, a, rows, b, cols);
    return backtrace_pairs(g, a, rows, b, cols, out);
}

/* seed_alignment: the rotation (and reflection) of the sketch region's neighbours with the lowest
 * distance to the metric region's (ties: the smallest offset, unreflected first; 'first' keeps
 * offset 0), and the pairs it aligns. Returns the number of pairs; *reflected is set. Orders too
 * long for the table are aligned bit-parallel (bitalign.c; the same pairs). */
static int32_t seed_pairs(Planar *p, int32_t v, int32_t w, int rotation_min, int reflections, int *reflected,
                          int32_t *out)
{
    const Graphs *g = &p->g;
    const int32_t *a = g->nb1 + g->off1[v], *b = g->nb2 + g->off2[w];
    int32_t rows = g->off1[v + 1] - g->off1[v], cols = g->off2[w + 1] - g->off2[w];
    *reflected = 0;
    if (rows > 0 && cols > 0 && (int64_t)(rows + 1) * (cols + 1) > g->table_cells) {
        return bit_seed_pairs(p, v, w, rotation_min, reflections, reflected, out);
    }
    if (!rotation_min || rows <= 1) {
        return aligned_index_pairs(g, a, rows, b, cols, out);
    }
    int32_t *rotated = g->row_buffer;
    int32_t best = -1, best_offset = 0;
    int best_reflected = 0;
    for (int flip = 0; flip <= (reflections ? 1 : 0) && best != 0; flip++) {
        for (int32_t offset = 0; offset < rows; offset++) {
            for (int32_t k = 0; k < rows; k++) {
                int32_t position = (offset + k) % rows;
                rotated[k] = flip ? a[rows - 1 - position] : a[position];
            }
            int32_t distance = fill_table(g, rotated, rows, b, cols);
            if (best < 0 || distance < best) {
                best = distance;
                best_offset = offset;
                best_reflected = flip;
                if (distance == 0) {
                    break;
                }
            }
        }
    }
    for (int32_t k = 0; k < rows; k++) {
        int32_t position = (best_offset + k) % rows;
        rotated[k] = best_reflected ? a[rows - 1 - position] : a[position];
    }
    *reflected = best_reflected;
    return aligned_index_pairs(g, rotated, rows, b, cols, out);
}

/* arc(): the elements strictly between positions start and stop walking forward (all the others
 * after start when they are equal). Returns the length written to ``out``. */
static int32_t arc(const int32_t *order, int32_t size, int32_t start, int32_t stop, int32_t *out)
{
    int32_t n = 0;
    if (start < stop) {
        for (int32_t k = start + 1; k < stop; k++) {
            out[n++] = order[k];
        }
    } else {
        for (int32_t k = start + 1; k < size; k++) {
            out[n++] = order[k];
        }
        for (int32_t k = 0; k < stop; k++) {
            out[n++] = order[k];
        }
    }
    return n;
}

/* The bit of a (sketch, metric) pair in the consumed bitmap (one bit a pair: 2.3 MB for two
 * 4250-region maps, against 18 MB as bytes, and emptied at every match). */
static inline int is_consumed(const uint8_t *consumed, int64_t cell)
{
    return (consumed[cell >> 3] >> (cell & 7)) & 1;
}

static inline void consume(uint8_t *consumed, int64_t cell)
{
    consumed[cell >> 3] |= (uint8_t)(1u << (cell & 7));
}

/* Queue the aligned pairs whose two regions are both unseen in this hypothesis, in order; mark them
 * seen and consumed (a seed equal to one no longer starts a hypothesis). Returns the new tail. */
static int32_t enqueue(const int32_t *aligned, int32_t count, int32_t *queue, int32_t tail, int32_t *seen1,
                       int32_t *seen2, int32_t stamp, uint8_t *consumed, int32_t n2)
{
    for (int32_t q = 0; q < count; q++) {
        int32_t a = aligned[2 * q], b = aligned[2 * q + 1];
        if (seen1[a] == stamp || seen2[b] == stamp) {
            continue;
        }
        queue[2 * tail] = a;
        queue[2 * tail + 1] = b;
        tail++;
        seen1[a] = stamp;
        seen2[b] = stamp;
        consume(consumed, (int64_t)a * n2 + b);
    }
    return tail;
}

static int32_t *int_sequence_arg(PyObject *seeds, Py_ssize_t *count)
{
    PyObject *fast = PySequence_Fast(seeds, "planar_match: seeds must be a sequence of (int, int)");
    if (fast == NULL) {
        return NULL;
    }
    Py_ssize_t n = PySequence_Fast_GET_SIZE(fast);
    int32_t *out = malloc(sizeof(int32_t) * 2 * (size_t)(n > 0 ? n : 1));
    if (out == NULL) {
        Py_DECREF(fast);
        PyErr_NoMemory();
        return NULL;
    }
    PyObject **items = PySequence_Fast_ITEMS(fast);
    for (Py_ssize_t k = 0; k < n; k++) {
        PyObject *pair = items[k];
        if (!PyTuple_Check(pair) || PyTuple_GET_SIZE(pair) != 2) {
            PyErr_SetString(PyExc_TypeError, "planar_match: every seed must be a (int, int) tuple");
            goto fail;
        }
        for (int side = 0; side < 2; side++) {
            long value = PyLong_AsLong(PyTuple_GET_ITEM(pair, side));
            if (value == -1 && PyErr_Occurred()) {
                goto fail;
            }
            out[2 * k + side] = (int32_t)value;
        }
    }
    Py_DECREF(fast);
    *count = n;
    return out;
fail:
    Py_DECREF(fast);
    free(out);
    return NULL;
}

/* The pair cost of cell ``k`` (see PairCosts). */
static inline double pair_cost(const PairCosts *costs, int64_t k)
{
    return costs->substitutions ? (costs->cost[k] > costs->above ? 1.0 : 0.0) : costs->cost[k];
}

/* Positions of the popped pair's locked neighbours, in the sketch order: (q, r) with order1[q]
 * matched (``matched1[u] == stamp``) to order2[r], r the last position as planar.py's dict of
 * positions has it. Long metric orders are looked up through ``where`` (a building corridor's
 * thousands of neighbours), short ones by a scan. */
static int32_t find_locks(const int32_t *order1, int32_t size1, const int32_t *order2, int32_t size2,
                          const int32_t *matched1, const int32_t *partner, int32_t stamp, int32_t *where,
                          int32_t *locks)
{
    int32_t n_locks = 0;
    int listed = size2 > 16;
    if (listed) {
        for (int32_t r = 0; r < size2; r++) {
            where[order2[r]] = r + 1;
        }
    }
    for (int32_t q = 0; q < size1; q++) {
        int32_t u = order1[q];
        if (matched1[u] != stamp) {
            continue;
        }
        int32_t target = partner[u], found = -1;
        if (listed) {
            found = where[target] - 1;
        } else {
            for (int32_t r = size2 - 1; r >= 0; r--) {
                if (order2[r] == target) {
                    found = r;
                    break;
                }
            }
        }
        if (found >= 0) {
            locks[2 * n_locks] = q;
            locks[2 * n_locks + 1] = found;
            n_locks++;
        }
    }
    if (listed) {
        for (int32_t r = 0; r < size2; r++) {
            where[order2[r]] = 0;
        }
    }
    return n_locks;
}

/* One planar match from ``seeds`` (n_seeds >= 1, inside the graphs) over ``p->g.same``; ``costs``
 * NULL: not weighted. The best pairs are left in ``p->best_pairs``. Needs no Python (the GIL may
 * be released); out of memory, it stops with ``p->failed`` set. Stamps are unique over the calls
 * on one Planar, so they are never cleared. */
void planar_run(Planar *p, const int32_t *seeds, Py_ssize_t n_seeds, const PairCosts *costs, PlanarOutcome *out)
{
    Graphs *g = &p->g;
    int32_t n1 = g->n1, n2 = g->n2;
    int weighted = costs != NULL;
    double weight = weighted ? costs->weight : 0.0;
    int32_t *seen1 = p->stamps, *matched1 = p->stamps + n1, *seen2 = p->stamps + 2 * n1;
    int32_t *arc1 = p->arc1, *arc2 = p->arc2, *locks = p->locks, *aligned = p->aligned, *queue = p->queue;
    int32_t *pairs = p->pairs, *best_pairs = p->best_pairs, *partner = p->partner;
    uint8_t *consumed = p->consumed;
    memset(consumed, 0, ((size_t)n1 * (size_t)n2 + 7) / 8);
    bit_reset(p);
    memset(out, 0, sizeof(*out));

    int64_t single_structure = (int64_t)(n1 - 1) + (n2 - 1) + p->edges1 + p->edges2;
    Py_ssize_t best_seed = 0;
    double best_term = 0.0;
    if (weighted) {
        best_term = weight * pair_cost(costs, (int64_t)seeds[0] * n2 + seeds[1]);
        for (Py_ssize_t k = 1; k < n_seeds; k++) {
            double term = weight * pair_cost(costs, (int64_t)seeds[2 * k] * n2 + seeds[2 * k + 1]);
            if (term < best_term) {
                best_term = term;
                best_seed = k;
            }
        }
    }
    int32_t n_best = 1;
    best_pairs[0] = seeds[2 * best_seed];
    best_pairs[1] = seeds[2 * best_seed + 1];
    int64_t best_structure = single_structure;
    double best_cost = (double)single_structure + best_term;
    int64_t hypotheses = n_seeds, expanded = 0;

    for (Py_ssize_t k = 0; k < n_seeds; k++) {
        int32_t v = seeds[2 * k], w = seeds[2 * k + 1];
        if (is_consumed(consumed, (int64_t)v * n2 + w)) {
            continue;
        }
        consume(consumed, (int64_t)v * n2 + w);
        expanded++;
        int32_t stamp = ++p->stamp;
        int reflected = 0;
        int32_t n_aligned = seed_pairs(p, v, w, p->rotation_min, p->reflections, &reflected, aligned);
        if (p->failed) {
            return;
        }
        seen1[v] = stamp;
        seen2[w] = stamp;
        matched1[v] = stamp;
        partner[v] = w;
        int32_t n_pairs = 1, head = 0, tail = 0;
        pairs[0] = v;
        pairs[1] = w;
        tail = enqueue(aligned, n_aligned, queue, tail, seen1, seen2, stamp, consumed, n2);
        while (head < tail) {
            int32_t vertex = queue[2 * head], other = queue[2 * head + 1];
            head++;
            if (matched1[vertex] != stamp) {
                pairs[2 * n_pairs] = vertex;
                pairs[2 * n_pairs + 1] = other;
                n_pairs++;
                matched1[vertex] = stamp;
                partner[vertex] = other;
            }
            int32_t size1 = g->off1[vertex + 1] - g->off1[vertex], size2 = g->off2[other + 1] - g->off2[other];
            if (size1 <= 1 || size2 <= 1) {
                continue; /* one neighbour on either side: every arc between locks is empty */
            }
            const int32_t *order2 = g->nb2 + g->off2[other];
            const int32_t *base1 = g->nb1 + g->off1[vertex];
            int32_t *order1 = g->row_buffer;
            for (int32_t q = 0; q < size1; q++) {
                order1[q] = reflected ? base1[size1 - 1 - q] : base1[q];
            }
            int32_t n_locks = find_locks(order1, size1, order2, size2, matched1, partner, stamp, p->where2, locks);
            for (int32_t l = 0; l < n_locks; l++) {
                int32_t next = (l + 1) % n_locks;
                int32_t start1 = locks[2 * l], start2 = locks[2 * l + 1];
                /* The elements strictly between two locks, walking forward (all the others for one). */
                int32_t length1 = locks[2 * next] - start1 - 1, length2 = locks[2 * next + 1] - start2 - 1;
                length1 += length1 < 0 ? size1 : 0;
                length2 += length2 < 0 ? size2 : 0;
                if (length1 == 0 || length2 == 0) {
                    continue;
                }
                const int32_t *found_pairs = aligned;
                int32_t found;
                if ((int64_t)(length1 + 1) * (length2 + 1) > g->table_cells) {
                    /* Arcs of a corridor: bit-parallel, once per match (the same pairs). */
                    found_pairs = bit_arc_pairs(p, vertex, other, reflected, start1 + 1 == size1 ? 0 : start1 + 1,
                                                length1, start2 + 1 == size2 ? 0 : start2 + 1, length2, &found);
                    if (found_pairs == NULL) {
                        return;
                    }
                } else {
                    arc(order1, size1, start1, locks[2 * next], arc1);
                    arc(order2, size2, start2, locks[2 * next + 1], arc2);
                    /* order1 lives in row_buffer, which the alignment does not touch (it is only
                     * the seed alignment's rotation buffer). */
                    found = aligned_index_pairs(g, arc1, length1, arc2, length2, aligned);
                }
                tail = enqueue(found_pairs, found, queue, tail, seen1, seen2, stamp, consumed, n2);
            }
        }
        hypotheses++;
        /* Edges among the matched vertices, each seen from both ends. At the end of an expansion
         * every queued pair is matched, so "seen" is "matched" on both sides. */
        int64_t inner1 = 0, inner2 = 0;
        for (int32_t q = 0; q < n_pairs; q++) {
            int32_t a = pairs[2 * q], b = pairs[2 * q + 1];
            for (int32_t e = g->off1[a]; e < g->off1[a + 1]; e++) {
                inner1 += matched1[g->nb1[e]] == stamp;
            }
            for (int32_t e = g->off2[b]; e < g->off2[b + 1]; e++) {
                inner2 += seen2[g->nb2[e]] == stamp;
            }
        }
        inner1 /= 2;
        inner2 /= 2;
        int64_t structure = (int64_t)(n1 - n_pairs) + (n2 - n_pairs) + (p->edges1 - inner1) + (p->edges2 - inner2)
                            + (inner1 > inner2 ? inner1 - inner2 : inner2 - inner1);
        double cost = (double)structure;
        if (weighted) {
            double sum = 0.0;
            for (int32_t q = 0; q < n_pairs; q++) {
                sum += pair_cost(costs, (int64_t)pairs[2 * q] * n2 + pairs[2 * q + 1]);
            }
            cost = (double)structure + weight * sum;
        }
        /* A small tolerance so that float sums of pair costs do not break the earliest-wins rule. */
        if (cost < best_cost - 1e-12) {
            best_cost = cost;
            best_structure = structure;
            n_best = n_pairs;
            memcpy(best_pairs, pairs, sizeof(int32_t) * 2 * (size_t)n_pairs);
        }
    }
    out->n_pairs = n_best;
    out->structure = best_structure;
    out->cost = best_cost;
    out->hypotheses = hypotheses;
    out->expanded = expanded;
}

/* planar_match(off1, nb1, off2, nb2, edges1, edges2, same, seeds, pair_costs, weight, rotation_min,
 * reflections, table_cells) -> (pairs, cost, structural_cost, hypotheses, seeds_expanded).
 * ``pair_costs`` None: not weighted (the cost is the structural cost, an int). ``table_cells``:
 * alignments of more cells are bit-parallel (the same pairs either way). */
KERNEL(planar_match)
{
    if (check_nargs("planar_match", nargs, 13) < 0) {
        return NULL;
    }
    Planar p;
    Py_buffer views[6];
    int n_views = 0;
    PyObject *result = NULL;
    int32_t *seeds = NULL;
    if (planar_open(&p, args, views, "planar_match", args[12]) < 0) {
        return NULL;
    }
    n_views = 4;
    if (get_buffer(args[6], 1, 'b', 2, "planar_match: same", &views[n_views]) < 0) goto done;
    n_views++;
    int weighted = args[8] != Py_None;
    const double *costs = NULL;
    if (weighted) {
        if (get_buffer(args[8], 8, 'f', 2, "planar_match: pair_costs", &views[n_views]) < 0) goto done;
        costs = views[n_views].buf;
        n_views++;
    }
    double weight = PyFloat_AsDouble(args[9]);
    p.rotation_min = (int)PyLong_AsLong(args[10]);
    p.reflections = (int)PyLong_AsLong(args[11]);
    if (PyErr_Occurred()) goto done;
    int32_t n1 = p.g.n1, n2 = p.g.n2;
    if (views[4].shape[0] != n1 || views[4].shape[1] != n2
        || (weighted && (views[5].shape[0] != n1 || views[5].shape[1] != n2))) {
        PyErr_SetString(PyExc_ValueError, "planar_match: same and pair_costs must be n1 x n2");
        goto done;
    }
    p.g.same = views[4].buf;
    Py_ssize_t n_seeds = 0;
    seeds = int_sequence_arg(args[7], &n_seeds);
    if (seeds == NULL) goto done;
    for (Py_ssize_t k = 0; k < n_seeds; k++) {
        if (seeds[2 * k] < 0 || seeds[2 * k] >= n1 || seeds[2 * k + 1] < 0 || seeds[2 * k + 1] >= n2) {
            PyErr_SetString(PyExc_IndexError, "planar_match: a seed is outside the graphs");
            goto done;
        }
    }
    if (n_seeds == 0) {
        PyErr_SetString(PyExc_ValueError, "planar_match: no seed");
        goto done;
    }
    PlanarOutcome outcome;
    PairCosts pair_costs = {costs, weight, 0, 0.0};
    Py_BEGIN_ALLOW_THREADS
    planar_run(&p, seeds, n_seeds, weighted ? &pair_costs : NULL, &outcome);
    Py_END_ALLOW_THREADS
    if (p.failed) {
        PyErr_NoMemory();
        goto done;
    }
    result = planar_outcome_tuple(p.best_pairs, &outcome, weighted);
done:
    for (int k = 0; k < n_views; k++) {
        PyBuffer_Release(&views[k]);
    }
    free(seeds);
    planar_close(&p);
    return result;
}
