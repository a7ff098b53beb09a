/*
 * rt_thread.c - a thread in the real-time class when the system allows it
 * (palp_rt_thread.h).
 */
#include "palp_rt_thread.h"

#include <sched.h>

int palp_rt_thread_start(pthread_t *th, int priority, void *(*fn)(void *), void *arg, int *rt_ok) {
  int created = 0;
  if (priority > 0) {
    pthread_attr_t attr;
    struct sched_param sp = {.sched_priority = priority};
    pthread_attr_init(&attr);
    pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
    pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
    pthread_attr_setschedparam(&attr, &sp);
    created = pthread_create(th, &attr, fn, arg) == 0;
    pthread_attr_destroy(&attr);
  }
  if (rt_ok) *rt_ok = created;
  if (!created && pthread_create(th, NULL, fn, arg) != 0) return -1;
  return 0;
}
