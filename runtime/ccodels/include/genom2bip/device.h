/* genom2bip/device.h: the devices the controller gives C codels by name (not part of GenoM3's interface).
 *
 * A codel that drives hardware opens it itself (a serial port, a socket).  Under genom2bip the device may
 * be a simulator that lives in the controller's process (DALA's base is an ir-sim robot): the codels' Python
 * side offers it as a table of C-callable functions (C_DEVICES in a module of the Python codels), and
 * genom2bip_device(name) returns that table, or NULL when there is none (no such device, or the codels run
 * in a process of their own).  The table's layout is an agreement between the codels and the device.
 */
#ifndef H_GENOM2BIP_DEVICE
#define H_GENOM2BIP_DEVICE

#ifdef __cplusplus
extern "C" {
#endif

void *genom2bip_device(const char *name);

#ifdef __cplusplus
}
#endif

#endif /* H_GENOM2BIP_DEVICE */
