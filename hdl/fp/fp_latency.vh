// Pipeline latencies of the binary32 units, in clock cycles.
//
// A unit with latency L has L registers on every path from its inputs to y,
// the last of which drives y. Operands presented before rising edge t are
// sampled by edge t; y holds their result from just after edge t+L-1 until
// edge t+L. So y appears L rising edges after the inputs are presented,
// counting the sampling edge as the first. A new operation may be presented
// before every edge.
//
// Each unit first registers its operands (its stage 0): the core's
// schedule decode and operand multiplexers end there, so that no path runs
// from them into a unit's arithmetic (placed and routed, this took the
// core from 19 to 30 MHz for one cycle of latency per unit; docs/hw.md).
`ifndef FP_LATENCY_VH
`define FP_LATENCY_VH
`define FP_MUL_LAT 3
`define FP_ADD_LAT 4
`define FP_DIV_LAT 13
`endif
