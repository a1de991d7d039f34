/* genom3/c/context.h (genom2bip runtime): the last argument of every codel.
 *
 * raise(ex, detail, size, self) records exception ex with a copy of its detail (size bytes, none when
 * detail is NULL) and returns ex, for the codel to return; raised(&ex, self) gives back the exception
 * recorded last and its detail (NULL when none).  data belongs to the controller that runs the codels.
 */
#ifndef GENOM2BIP_GENOM3_C_CONTEXT_H
#define GENOM2BIP_GENOM3_C_CONTEXT_H

#include <stddef.h>

#include "genom3/c/event.h"

struct genom_context_data;
struct genom_context_iface;
typedef const struct genom_context_iface *genom_context;

struct genom_context_iface {
  genom_event (*raise)(genom_event ex, void *detail, size_t size, genom_context self);
  const void *(*raised)(genom_event *ex, genom_context self);
  struct genom_context_data *data;
};

#endif /* GENOM2BIP_GENOM3_C_CONTEXT_H */
