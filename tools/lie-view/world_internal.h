/* Private to lie-view's world.c and update.c. */
#ifndef LIE_VIEW_WORLD_INTERNAL_H
#define LIE_VIEW_WORLD_INTERNAL_H

#include "view.h"

#include <time.h>

struct view_world {
    pthread_rwlock_t lock;
    char *input;
    view_world_options opt;
    lie_scene *scene;
    lie_cache *cache;          /* NULL for a glTF input: full visibility, no edits to units */
    lie_rt *rt;
    lie_lie_vis *vis;
    lie_vis_oracle oracle;     /* vis's oracle, pending units sent to Embree */
    const lie_vis_oracle *inner;
    uint8_t *pending;          /* per unit (tri * n_emitters + e) */
    size_t n_units;
    _Atomic int64_t n_pending;
    int64_t pending_max;
    _Atomic uint64_t version;
    uint64_t epoch;            /* edits applied: a constructor step from an older epoch is dropped */
    uint64_t env_gen;          /* constructor swaps: ray segment trees older than it are stale */
    double last_ms;
    double *update_ms;
    int n_update_ms;
    /* the session's edits: live groups (undo pops), undone groups (redo pops) */
    char **live, **undone;
    int n_live, n_undone;
    /* the constructor */
    pthread_t ctor;
    int ctor_started, quit;
    pthread_mutex_t cm;
    pthread_cond_t ccv;        /* work arrived, or pending reached 0 */
};

lie_box3 *world_own_boxes(const lie_scene *s);
lie_status world_load_base(view_world *w, lie_scene **out, lie_error *err);
lie_status world_make_oracle(view_world *w, lie_error *err);
/* Triangles or emitters changed in number: rebuild the whole env for the
 * scene now (write lock held, rt current). */
lie_status world_rebuild_all(view_world *w, lie_error *err);
void *world_constructor_main(void *arg);

#endif
