// The cost of reading the thread CPU clock, which SMPI reads twice a burst (docs/smpi.md, "The
// charge of an empty burst"): gcc -O2 clock_cost.c -o clock_cost && ./clock_cost
#include <stdio.h>
#include <time.h>
int main(){ struct timespec a,b,t; clock_gettime(CLOCK_MONOTONIC,&a); for(int i=0;i<1000000;i++) clock_gettime(CLOCK_THREAD_CPUTIME_ID,&t); clock_gettime(CLOCK_MONOTONIC,&b);
printf("thread cputime: %.1f ns/call\n", ((b.tv_sec-a.tv_sec)*1e9+(b.tv_nsec-a.tv_nsec))/1e6);
struct timespec x,y; double mn=1e9; for(int i=0;i<100000;i++){clock_gettime(CLOCK_THREAD_CPUTIME_ID,&x);clock_gettime(CLOCK_THREAD_CPUTIME_ID,&y); double d=(y.tv_sec-x.tv_sec)*1e9+(y.tv_nsec-x.tv_nsec); if(d<mn)mn=d;} printf("min back-to-back delta %.0f ns\n",mn);}
