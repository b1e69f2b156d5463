/* SPDX-License-Identifier: Apache-2.0 */
/* Private to lie-view's world.c and update.c. */
#ifndef LIE_VIEW_WORLD_INTERNAL_H
#define LIE_VIEW_WORLD_INTERNAL_H

#include "view.h"

#include <time.h>

/* One undoable group of edits, and the edit that restores what it changed
 * (NULL: it added an object, which no edit takes out again). */
typedef struct view_group {
    lie_edit *edit, *inverse;
} view_group;

struct view_world {
    pthread_rwlock_t lock;
    char *input;
    view_world_options opt;
    lie_scene *scene;
    lie_cache *cache;          /* NULL for a glTF input: full visibility, no units */
    /* the asynchronous constructor (lib/update, lie_ctor) on a glTF input or a
     * partial cache; NULL where lib/update's §5 update keeps a whole cache */
    lie_ctor *ctor;
    uint64_t loaded_hash;      /* the scene as loaded (a saved cache's provenance) */
    int n_edits0;              /* the cache's edit log as loaded */
    lie_update *up;            /* lib/update: the §5 update in two phases */
    lie_rt *rt;                /* Embree over the scene as edited */
    lie_env *render_env;       /* the update's latest snapshot: pending units are LIE_CLASS_NONE */
    lie_env_shadows *vis;          /* over render_env */
    _Atomic int64_t n_pending;
    _Atomic int dirty;         /* edited since the update last committed */
    int64_t pending_max;
    _Atomic uint64_t version;
    uint64_t epoch;            /* edits applied: a snapshot taken before the last edit is dropped */
    double last_ms;
    double *update_ms;
    int n_update_ms;
    /* the session: every edit applied, in order (what --record writes and
     * --save logs); the groups undo pops and redo pops */
    lie_edit *applied;
    view_group *live;
    lie_edit **undone;
    int n_live, n_undone;
    /* the constructor */
    pthread_t ctor_thread;
    int ctor_started, quit, failed;
    int held, stepping;        /* (cm) view_world_hold's count; a step is running */
    lie_error ctor_err;
    pthread_mutex_t cm;
    pthread_cond_t ccv;        /* work arrived, or pending reached 0 */
};

/* (Re)create the LIE oracle over render_env (write lock held or no other thread). */
lie_status world_make_oracle(view_world *w, lie_error *err);
void *world_constructor_main(void *arg);
void world_free_session(view_world *w);

#endif
