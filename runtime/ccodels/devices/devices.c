/* genom2bip_device() (genom2bip/device.h), linked into every codel library.
 *
 * The controller sets genom2bip_devices when it loads the library; until then, and in a library run in a
 * process of its own, every device is NULL.
 */
#include <stddef.h>

void *(*genom2bip_devices)(const char *name) = NULL;

void *genom2bip_device(const char *name)
{
  return genom2bip_devices && name ? genom2bip_devices(name) : NULL;
}
