/* MAORIS ripple merging and door removal in C, tracking the contact counts across fusions
 * (port of ../kernels/fusion.py, whose docstrings explain the method).
 *
 * A fusion visits the pixels around the absorbed zone once and applies only the changes of the
 * counts (contacts_fuse), so the two steps that read contact percentages while they fuse never
 * count from scratch. The tracking state comes from contact_tracking.start_tracking; its table
 * arrays are the numpy arrays it holds until the table must grow, then arrays of this run
 * (freed at its end: Python never reads the state again after the step). */
#include "contact_rules.h"
#include "contact_table.h"
#include "graph.h"
#include "kernels.h"

/* Border pixels of a fusion are loaded this many candidates ahead. */
#define AHEAD 6
/* The smallest hash sets of a fusion (bits): small fusions probe a prefix of the scratch sets. */
#define MIN_BITS 8

/* The tracking state (parent, pixels, following, head, tail, keys, counts, meta, slots, total)
 * and the tracking's (original, compact_of). */
typedef struct {
    int32_t *parent, *pixels, *following, *head, *tail;
    int64_t n_parent, n_original;
    int64_t *slots, *total;
    Table table;
    int32_t *original, *compact_of;
} Tracking;

/* The scratch arrays of contacts_fuse (empty between fusions; they only ever grow). */
typedef struct {
    int32_t *walk, *walk_pixels, *affected;
    int64_t n_walk_room, n_seen, n_change;
    int64_t *seen, *used, *change_keys, *change_counts, *changed;
} Scratch;

static void scratch_release(Scratch *scratch)
{
    free(scratch->walk), free(scratch->walk_pixels), free(scratch->affected), free(scratch->seen);
    free(scratch->used), free(scratch->change_keys), free(scratch->change_counts), free(scratch->changed);
}

/* _with_room's growth of the pixel arrays (walk, walk_pixels) to ``size``. */
static int grow_walk(Scratch *s, int64_t size)
{
    free(s->walk), free(s->walk_pixels);
    s->walk = malloc((size_t)size * sizeof(int32_t));
    s->walk_pixels = malloc((size_t)size * sizeof(int32_t));
    s->n_walk_room = size;
    return s->walk == NULL || s->walk_pixels == NULL ? -1 : 0;
}

static int grow_seen(Scratch *s, int64_t size)
{
    free(s->seen), free(s->affected), free(s->used);
    s->seen = filled_i64(size, EMPTY);
    s->affected = malloc((size_t)(size / 4) * sizeof(int32_t));
    s->used = malloc((size_t)(size / 4) * sizeof(int64_t));
    s->n_seen = size;
    return s->seen == NULL || s->affected == NULL || s->used == NULL ? -1 : 0;
}

static int grow_change(Scratch *s, int64_t size)
{
    free(s->change_keys), free(s->change_counts), free(s->changed);
    s->change_keys = filled_i64(size, EMPTY);
    s->change_counts = calloc((size_t)size, sizeof(int64_t));
    s->changed = malloc((size_t)(size / 2) * sizeof(int64_t));
    s->n_change = size;
    return s->change_keys == NULL || s->change_counts == NULL || s->changed == NULL ? -1 : 0;
}

/* _new_scratch. */
static int scratch_new(Scratch *s)
{
    memset(s, 0, sizeof(*s));
    return grow_walk(s, 1024) < 0 || grow_seen(s, 4096) < 0 || grow_change(s, 4096) < 0 ? -1 : 0;
}

/* _gather: the candidates of compact zone ``here`` and their pixels into the walk arrays (as
 * many as fit); returns how many there are. */
static int64_t gather(const Tracking *t, int64_t here, Scratch *s)
{
    int64_t n_walk = 0;
    for (int64_t candidate = t->head[here]; candidate != -1; candidate = t->following[candidate]) {
        if (n_walk < s->n_walk_room) {
            s->walk[n_walk] = (int32_t)candidate;
            s->walk_pixels[n_walk] = t->pixels[candidate];
        }
        n_walk += 1;
    }
    return n_walk;
}

/* _room_needed: at most 9 affected pixels per candidate, and 9 count changes per affected pixel. */
static int room_needed(int64_t n_walk, const Scratch *s, const Table *table)
{
    return n_walk > s->n_walk_room || 4 * 9 * n_walk > s->n_seen || 2 * 81 * n_walk > s->n_change
           || 2 * (table->meta[0] + 81 * n_walk) > table->size;
}

/* _with_room: grow what must grow for a fusion of n_walk candidates. 0, or -1 out of memory. */
static int with_room(int64_t n_walk, Scratch *s, Table *table)
{
    if (n_walk > s->n_walk_room && grow_walk(s, 2 * n_walk) < 0) {
        return -1;
    }
    if (4 * 9 * n_walk > s->n_seen) {
        int64_t size = s->n_seen;
        while (4 * 9 * n_walk > size) {
            size *= 2;
        }
        if (grow_seen(s, size) < 0) {
            return -1;
        }
    }
    if (2 * 81 * n_walk > s->n_change) {
        int64_t size = s->n_change;
        while (2 * 81 * n_walk > size) {
            size *= 2;
        }
        if (grow_change(s, size) < 0) {
            return -1;
        }
    }
    return table_reserve(table, 81 * n_walk);
}

static inline void prefetch_rows(const int32_t *labels, int64_t pixel, int64_t width)
{
    PREFETCH(labels + pixel - width - 1);
    PREFETCH(labels + pixel - 1);
    PREFETCH(labels + pixel + width - 1);
}

/* _mark: append ``pixel`` to the affected pixels unless it has no zone or was seen already in
 * this fusion (a hash set of its pixels). */
static inline int64_t mark(int64_t pixel, const int32_t *labels, Scratch *s, int64_t bits, int64_t n_affected)
{
    if (labels[pixel] == 0) {
        return n_affected;
    }
    int64_t slot = probe(s->seen, s->n_seen, pixel, bits);
    if (s->seen[slot] == pixel) {
        return n_affected;
    }
    s->seen[slot] = pixel;
    s->affected[n_affected] = (int32_t)pixel;
    s->used[n_affected] = slot;
    return n_affected + 1;
}

/* _contacts_fuse: fuse compact zone ``here`` (n_walk candidates, gathered) into ``into`` in the
 * contact state, whose arrays have room (room_needed). */
static void contacts_fuse(int64_t here, int64_t into, int64_t n_walk, const int32_t *labels, int64_t width,
                          Tracking *t, Scratch *s)
{
    int32_t *parent = t->parent, *following = t->following;
    int64_t base = t->n_parent;
    int64_t seen_bits = bits_of(4 * 9 * n_walk);
    seen_bits = seen_bits > MIN_BITS ? seen_bits : MIN_BITS;
    for (int64_t i = 0; i < (n_walk < AHEAD ? n_walk : AHEAD); i++) {
        prefetch_rows(labels, s->walk_pixels[i], width);
    }
    int64_t n_affected = 0, kept_head = -1, kept_tail = -1;
    for (int64_t i = 0; i < n_walk; i++) {
        if (i + AHEAD < n_walk) {
            prefetch_rows(labels, s->walk_pixels[i + AHEAD], width);
        }
        int64_t candidate = s->walk[i], pixel = s->walk_pixels[i];
        if (is_inner(labels, parent, pixel, width, here)) {
            continue; /* inside now: dropped for good */
        }
        following[candidate] = -1;
        if (kept_tail == -1) {
            kept_head = candidate;
        } else {
            following[kept_tail] = (int32_t)candidate;
        }
        kept_tail = candidate;
        int64_t up = pixel - width, down = pixel + width;
        n_affected = mark(up - 1, labels, s, seen_bits, n_affected);
        n_affected = mark(up, labels, s, seen_bits, n_affected);
        n_affected = mark(up + 1, labels, s, seen_bits, n_affected);
        n_affected = mark(pixel - 1, labels, s, seen_bits, n_affected);
        n_affected = mark(pixel, labels, s, seen_bits, n_affected);
        n_affected = mark(pixel + 1, labels, s, seen_bits, n_affected);
        n_affected = mark(down - 1, labels, s, seen_bits, n_affected);
        n_affected = mark(down, labels, s, seen_bits, n_affected);
        n_affected = mark(down + 1, labels, s, seen_bits, n_affected);
    }
    /* At most 9 count changes per affected pixel; the prefix stays at most half full. */
    int64_t change_bits = bits_of(2 * 9 * n_affected);
    change_bits = change_bits > MIN_BITS ? change_bits : MIN_BITS;
    int64_t n_changed = 0;
    int32_t around[9], partners[9];
    int64_t signs[9];
    for (int64_t k = 0; k < n_affected; k++) {
        int64_t own;
        neighbourhood(labels, parent, s->affected[k], width, around);
        int64_t n = recount(around, here, into, partners, signs, t->total, &own);
        for (int64_t i = 0; i < n; i++) {
            int64_t key = own * base + partners[i];
            int64_t slot = probe(s->change_keys, s->n_change, key, change_bits);
            if (s->change_keys[slot] == EMPTY) {
                s->change_keys[slot] = key;
                s->change_counts[slot] = 0;
                s->changed[n_changed++] = slot;
            }
            s->change_counts[slot] += signs[i];
        }
        s->seen[s->used[k]] = EMPTY;
    }
    for (int64_t k = 0; k < n_changed; k++) {
        int64_t slot = s->changed[k];
        if (s->change_counts[slot] != 0) {
            int64_t key = s->change_keys[slot];
            contact_add(t->slots, &t->table, base, key / base, key % base, s->change_counts[slot], parent);
        }
        s->change_keys[slot] = EMPTY;
    }
    parent[here] = (int32_t)into;
    if (kept_head != -1) {
        if (t->tail[into] == -1) {
            t->head[into] = (int32_t)kept_head;
        } else {
            following[t->tail[into]] = (int32_t)kept_head;
        }
        t->tail[into] = (int32_t)kept_tail;
    }
    t->head[here] = t->tail[here] = -1;
}

/* _fuse_tracked, with _with_room when the arrays must grow first. 0, or -1 out of memory. */
static int fuse_tracked(int64_t here, int64_t into, const int32_t *labels, int64_t width, Tracking *t, Scratch *s)
{
    int64_t n_walk = gather(t, here, s);
    if (room_needed(n_walk, s, &t->table)) {
        if (with_room(n_walk, s, &t->table) < 0) {
            return -1;
        }
        n_walk = gather(t, here, s);
    }
    contacts_fuse(here, into, n_walk, labels, width, t, s);
    return 0;
}

/* _contact_percent: integer percentage of compact ``zone``'s contour pixels having ``other``
 * in their 3x3. */
static inline int64_t contact_percent(Tracking *t, int64_t zone, int64_t other)
{
    if (t->total[zone] == 0) {
        return 0;
    }
    return floor_div(contact_get(t->slots, &t->table, t->n_parent, zone, other) * 100, t->total[zone]);
}

/* _restore_labels: undo _compact_labels, each label replaced by its current zone. */
static int restore_labels(int32_t *labels, int64_t n_labels, Tracking *t)
{
    int32_t *lookup = calloc((size_t)t->n_parent, sizeof(int32_t));
    if (lookup == NULL) {
        return -1;
    }
    for (int64_t label = 1; label < t->n_parent; label++) {
        lookup[label] = t->original[zone_of(label, t->parent) - 1];
    }
    relabel_in_place(labels, n_labels, lookup);
    free(lookup);
    return 0;
}

/* The arguments the two steps share: labels, width, size, alive, graph and tracking, from
 * args[first]. */
typedef struct {
    Array labels, size, alive;
    int64_t width;
    Graph graph;
    Tracking tracking;
} Step;

static int step_args(const char *kernel, PyObject *const *args, Step *step)
{
    Array original, compact_of, parent, pixels, following, head, tail, keys, counts, meta, slots, total;
    PyObject *const *tracking, *const *state;
    if (array_arg(args[0], NPY_INT32, 1, 0, "labels", &step->labels) || int_arg(args[1], "width", &step->width)
        || array_arg(args[2], NPY_INT64, 1, 0, "size", &step->size)
        || array_arg(args[3], NPY_BOOL, 1, 0, "alive", &step->alive) || graph_arg(args[4], "graph", &step->graph)
        || (tracking = tuple_arg(args[5], 3, "tracking")) == NULL
        || array_arg(tracking[0], NPY_INT32, 1, 0, "original", &original)
        || array_arg(tracking[1], NPY_INT32, 1, 0, "compact_of", &compact_of)
        || (state = tuple_arg(tracking[2], 10, "state")) == NULL
        || array_arg(state[0], NPY_INT32, 1, 0, "parent", &parent)
        || array_arg(state[1], NPY_INT32, 1, 0, "pixels", &pixels)
        || array_arg(state[2], NPY_INT32, 1, 0, "following", &following)
        || array_arg(state[3], NPY_INT32, 1, 0, "head", &head) || array_arg(state[4], NPY_INT32, 1, 0, "tail", &tail)
        || array_arg(state[5], NPY_INT64, 1, 0, "keys", &keys) || array_arg(state[6], NPY_INT64, 1, 0, "counts", &counts)
        || array_arg(state[7], NPY_INT64, 1, 0, "meta", &meta) || array_arg(state[8], NPY_INT64, 1, 0, "slots", &slots)
        || array_arg(state[9], NPY_INT64, 1, 0, "total", &total)) {
        return -1;
    }
    if (meta.size != META_SIZE || keys.size != counts.size || slots.size != parent.size * SLOTS
        || total.size != parent.size || head.size != parent.size || tail.size != parent.size
        || original.size + 1 != parent.size || compact_of.size != step->alive.size
        || step->size.size != step->alive.size) {
        PyErr_Format(PyExc_ValueError, "%s: the tracking state does not fit the graph", kernel);
        return -1;
    }
    step->tracking = (Tracking){
        parent.data, pixels.data, following.data, head.data, tail.data, parent.size, original.size,
        slots.data, total.data, {keys.data, counts.data, meta.data, keys.size, 0}, original.data, compact_of.data,
    };
    return 0;
}

/* removeRiplesv3: fuse each zone of the work list into the neighbour of closest value among
 * those it touches over ``ripples`` percent of its contour (through a breakable edge); the
 * neighbours of a fused zone are queued again. Returns 0, or -1 out of memory. */
static int ripples_loop(const int32_t *order, int64_t n_order, double ripples, Step *step)
{
    int32_t *records = step->graph.records, *nodes = step->graph.nodes;
    int32_t *labels = step->labels.data;
    int64_t *size = step->size.data;
    npy_bool *alive = step->alive.data;
    Tracking *t = &step->tracking;
    int64_t capacity = 2 * n_order > 16 ? 2 * n_order : 16;
    int32_t *queue = malloc((size_t)capacity * sizeof(int32_t));
    Scratch scratch;
    int status = scratch_new(&scratch);
    if (queue == NULL || status < 0) {
        goto done;
    }
    memcpy(queue, order, (size_t)n_order * sizeof(int32_t));
    int64_t start = 0, end = n_order;
    while (start < end) {
        int64_t zone = queue[start++];
        if (!alive[zone]) {
            continue;
        }
        int64_t zone_value = REC(records, zone, VALUE), here = t->compact_of[zone];
        int64_t best = -1, best_gap = 0;
        for (int64_t node = REC(records, zone, HEAD); node != -1; node = NODE(nodes, node, NEXT)) {
            int64_t other = NODE(nodes, node, NEIGHBOUR);
            /* numba compares the integer percentage with the float threshold in float64 */
            if (NODE(nodes, node | 1, ATTRIBUTE) == 0 && t->total[here] > 0
                && (double)contact_percent(t, here, t->compact_of[other]) >= ripples) {
                int64_t gap = REC(records, other, VALUE) - zone_value;
                gap = gap < 0 ? -gap : gap;
                if (best == -1 || gap < best_gap) {
                    best = other, best_gap = gap;
                }
            }
        }
        if (best == -1) {
            continue;
        }
        int64_t degree = REC(records, zone, DEGREE);
        if (end + degree > capacity) {
            int64_t grown_capacity = 2 * (end + degree);
            int32_t *grown = realloc(queue, (size_t)grown_capacity * sizeof(int32_t));
            if (grown == NULL) {
                status = -1;
                goto done;
            }
            queue = grown, capacity = grown_capacity;
        }
        for (int64_t node = REC(records, zone, HEAD); node != -1; node = NODE(nodes, node, NEXT)) {
            queue[end++] = NODE(nodes, node, NEIGHBOUR);
        }
        if (fuse_tracked(here, t->compact_of[best], labels, step->width, t, &scratch) < 0) {
            status = -1;
            goto done;
        }
        alive[zone] = 0;
        size[best] += size[zone];
        graph_fuse_edges(zone, best, records, nodes);
    }
    status = restore_labels(labels, step->labels.size, t);
done:
    free(queue);
    scratch_release(&scratch);
    table_release(&t->table);
    return queue == NULL ? -1 : status;
}

KERNEL(merge_ripples)
{
    Array order;
    double ripples;
    Step step;
    if (check_nargs("merge_ripples", nargs, 8) || array_arg(args[0], NPY_INT32, 1, 0, "order", &order)
        || float_arg(args[1], "ripples", &ripples) || step_args("merge_ripples", args + 2, &step)) {
        return NULL;
    }
    int status;
    Py_BEGIN_ALLOW_THREADS
    status = ripples_loop(order.data, order.size, ripples, &step);
    Py_END_ALLOW_THREADS
    if (status < 0) {
        return PyErr_NoMemory();
    }
    Py_RETURN_NONE;
}

/* _contact_sum: sum of the contact percentages of ``zone`` (compact id ``here``) over its
 * neighbours. */
static int64_t contact_sum(Tracking *t, const Graph *graph, int64_t zone, int64_t here)
{
    int64_t result = 0;
    for (int64_t node = REC(graph->records, zone, HEAD); node != -1; node = NODE(graph->nodes, node, NEXT)) {
        result += contact_percent(t, here, t->compact_of[NODE(graph->nodes, node, NEIGHBOUR)]);
    }
    return result;
}

/* removeDoors: zones in id order; one whose contact sum exceeds ``doors`` is fused into the
 * last neighbour whose sum is below ``doors``, else into its first neighbour, whose sum is
 * then recomputed. Returns 0, or -1 out of memory. */
static int doors_loop(double doors, Step *step)
{
    int32_t *records = step->graph.records, *nodes = step->graph.nodes;
    int64_t *size = step->size.data;
    npy_bool *alive = step->alive.data;
    Tracking *t = &step->tracking;
    int64_t *sums = calloc((size_t)(step->graph.n_records > 0 ? step->graph.n_records : 1), sizeof(int64_t));
    Scratch scratch;
    int status = scratch_new(&scratch);
    if (sums == NULL || status < 0) {
        status = -1;
        goto done;
    }
    for (int64_t k = 0; k < t->n_original; k++) {
        int64_t zone = t->original[k];
        sums[zone] = contact_sum(t, &step->graph, zone, k + 1);
    }
    for (int64_t k = 0; k < t->n_original; k++) {
        int64_t zone = t->original[k];
        /* numba compares the integer sums with the float threshold in float64 */
        if (!alive[zone] || (double)sums[zone] <= doors || REC(records, zone, DEGREE) == 0) {
            continue;
        }
        int64_t node = REC(records, zone, HEAD), target = NODE(nodes, node, NEIGHBOUR);
        for (; node != -1; node = NODE(nodes, node, NEXT)) {
            if ((double)sums[NODE(nodes, node, NEIGHBOUR)] < doors) {
                target = NODE(nodes, node, NEIGHBOUR);
            }
        }
        int64_t here = k + 1, into = t->compact_of[target];
        if (fuse_tracked(here, into, step->labels.data, step->width, t, &scratch) < 0) {
            status = -1;
            goto done;
        }
        alive[zone] = 0;
        size[target] += size[zone];
        graph_fuse_edges(zone, target, records, nodes);
        sums[target] = contact_sum(t, &step->graph, target, into);
    }
    status = restore_labels(step->labels.data, step->labels.size, t);
done:
    free(sums);
    scratch_release(&scratch);
    table_release(&t->table);
    return status;
}

KERNEL(remove_doors)
{
    double doors;
    Step step;
    if (check_nargs("remove_doors", nargs, 7) || float_arg(args[0], "doors", &doors)
        || step_args("remove_doors", args + 1, &step)) {
        return NULL;
    }
    int status;
    Py_BEGIN_ALLOW_THREADS
    status = doors_loop(doors, &step);
    Py_END_ALLOW_THREADS
    if (status < 0) {
        return PyErr_NoMemory();
    }
    Py_RETURN_NONE;
}
