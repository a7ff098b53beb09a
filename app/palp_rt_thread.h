/*
 * palp_rt_thread.h - a thread in the real-time class when the system allows it.
 *
 * The server's tick threads and factor helpers and the station's haptic thread
 * all want SCHED_FIFO (a tick preempted by a compiler or a browser is a missed
 * deadline), and all fall back to normal scheduling when it is refused (no
 * CAP_SYS_NICE or rtprio limit), saying so through *rt_ok.
 */
#ifndef PALP_RT_THREAD_H
#define PALP_RT_THREAD_H

#include <pthread.h>

/* Starts fn(arg) on *th: at SCHED_FIFO `priority` (1..99) when priority > 0 and
 * the kernel grants it, else at normal scheduling. *rt_ok (may be NULL) is set to
 * 1 when SCHED_FIFO was granted, 0 otherwise. Returns 0, or -1 when no thread
 * could be started at all. */
int palp_rt_thread_start(pthread_t *th, int priority, void *(*fn)(void *), void *arg, int *rt_ok);

#endif
