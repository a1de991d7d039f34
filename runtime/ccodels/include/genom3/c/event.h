/* genom3/c/event.h (genom2bip runtime): what a codel returns.
 *
 * An event is a C string naming a transition ("::comp::ether", "::comp::pause::main") or an exception
 * ("::comp::e_blocked"); NULL (genom_ok) is success.  Events and exception ids are defined in every
 * translation unit that includes the component's header, as weak symbols: the linker keeps one, so that
 * comparing an event with an id by address holds across the codels' files.
 */
#ifndef GENOM2BIP_GENOM3_C_EVENT_H
#define GENOM2BIP_GENOM3_C_EVENT_H

typedef const char *genom_event;

#define genom_weak __attribute__((weak, visibility("default")))
#ifdef __cplusplus
# define genom_extern_weak extern genom_weak
#else
# define genom_extern_weak genom_weak
#endif

#endif /* GENOM2BIP_GENOM3_C_EVENT_H */
