// IEEE 754 binary32 divider: y = a / b.
//
// Round to nearest, ties to even; subnormal inputs and results (gradual
// underflow); the sign of a quotient is the XOR of the operands' signs;
// x / 0 = inf for finite nonzero x, x / inf = 0 for finite x; any NaN
// operand, 0 / 0 and inf / inf give the canonical quiet NaN 0x7FC00000.
// Pipelined with latency `FP_DIV_LAT (13, see fp_latency.vh for the edge at
// which y appears), one operation per clock:
//   stage 0:     the operands registered;
//   stage 1:     classify, unpack (subnormals normalised), pre-shift the
//                dividend's significand so that the quotient is in [1, 2);
//   stages 2-11: restoring division, QB quotient bits per stage
//                (10 x 3 = 30 bits: 1 integer, 23 fraction, 6 for rounding);
//   stage 12:    sticky bit from the final remainder, round, pack.
// Three bits a stage keep a stage's chain of compare-and-subtract steps as
// short as the other units' stages; the core divides once a correction, so
// each stage costs one cycle a correction.
`include "fp_latency.vh"

module fp_div (
    input  wire        clk,
    input  wire [31:0] a_in,
    input  wire [31:0] b_in,
    output wire [31:0] y
);
`include "fp_common.vh"

    // ---- stage 0: the operands registered (fp_latency.vh says why) ----
    reg [31:0] a;
    reg [31:0] b;
    always @(posedge clk) begin
        a <= a_in;
        b <= b_in;
    end

    localparam QB = 3;       // quotient bits per division stage
    localparam NS = 10;      // division stages
    localparam QW = QB * NS; // quotient bits in all


    // Each stage is one clocked block: its combinational logic is written
    // with blocking assignments to temporaries (assigned before use on every
    // path, so they synthesise to wires) and its results go to the stage's
    // registers. This also evaluates each stage once per clock in a
    // simulator.

    // Operand classes.
    wire a_nan = (a[30:23] == 8'hFF) && (a[22:0] != 23'd0);
    wire b_nan = (b[30:23] == 8'hFF) && (b[22:0] != 23'd0);
    wire a_inf = (a[30:0] == 31'h7F80_0000);
    wire b_inf = (b[30:0] == 31'h7F80_0000);
    wire a_zero = (a[30:0] == 31'd0);
    wire b_zero = (b[30:0] == 31'd0);

    // Pipeline registers: entry 0 is written by stage 1, entry k by
    // division stage k (arrays with constant indices: plain registers).
    (* mem2reg *) reg          p_special [0:NS];  // a NaN, an infinity or a zero operand
    (* mem2reg *) reg [31:0]   p_spec_y  [0:NS];  // the result then
    (* mem2reg *) reg          p_s       [0:NS];  // sign
    (* mem2reg *) reg [11:0]   p_e       [0:NS];  // biased exponent of quotient bit QW-1
    (* mem2reg *) reg [23:0]   p_d       [0:NS];  // divisor significand
    (* mem2reg *) reg [25:0]   p_r       [0:NS];  // partial remainder, < 2 divisor
    (* mem2reg *) reg [QW-1:0] p_q       [0:NS];  // quotient bits so far (low end)

    // ---- stage 1 ----
    reg [35:0] s1_ua, s1_ub;
    reg        s1_pre;
    always @(posedge clk) begin
        s1_ua = fp_unpack(a);
        s1_ub = fp_unpack(b);
        // A dividend significand below the divisor's is doubled (and the
        // exponent lowered), so that the quotient is in [1, 2).
        s1_pre = s1_ua[23:0] < s1_ub[23:0];
        p_s[0]          <= a[31] ^ b[31];
        p_e[0]       <= s1_ua[35:24] - s1_ub[35:24] + 12'd127 - {11'd0, s1_pre};
        p_d[0]       <= s1_ub[23:0];
        p_r[0]       <= s1_pre ? {1'b0, s1_ua[23:0], 1'b0} : {2'b00, s1_ua[23:0]};
        p_q[0]     <= {QW{1'b0}};

        p_special[0] <= 1'b1;
        if (a_nan || b_nan || (a_zero && b_zero) || (a_inf && b_inf))
            p_spec_y[0] <= FP_QNAN;
        else if (a_inf || b_zero)
            p_spec_y[0] <= {a[31] ^ b[31], 8'hFF, 23'd0};
        else if (a_zero || b_inf)
            p_spec_y[0] <= {a[31] ^ b[31], 31'd0};
        else begin
            p_special[0]   <= 1'b0;
            p_spec_y[0] <= 32'd0;
        end
    end

    // ---- stages 2-11: QB steps of restoring division each ----
    // One statement per step (a simulator runs the unrolled chain quickly).
    genvar k;
    generate
        for (k = 1; k <= NS; k = k + 1) begin : g_div
            reg [25:0] r0, r1, r2, r3;
            reg [25:0] dv;
            reg [QB-1:0] q;
            always @(posedge clk) begin
                dv = {2'b00, p_d[k-1]};
                r0 = p_r[k-1];
                {q[2], r1} = (r0 >= dv) ? {1'b1, (r0 - dv) << 1} : {1'b0, r0 << 1};
                {q[1], r2} = (r1 >= dv) ? {1'b1, (r1 - dv) << 1} : {1'b0, r1 << 1};
                {q[0], r3} = (r2 >= dv) ? {1'b1, (r2 - dv) << 1} : {1'b0, r2 << 1};
                p_r[k]      <= r3;
                p_q[k]      <= {p_q[k-1][QW-QB-1:0], q};
                p_d[k]      <= dv[23:0];
                p_special[k]         <= p_special[k-1];
                p_spec_y[k] <= p_spec_y[k-1];
                p_s[k]               <= p_s[k-1];
                p_e[k]      <= p_e[k-1];
            end
        end
    endgenerate

    // ---- stage 12: sticky from the remainder, round, pack ----
    wire [QW-1:0] q_all = p_q[NS];  // q_all[QW-1] = 1
    wire [25:0]   r_all = p_r[NS];
    reg  [31:0]   r_y;
    always @(posedge clk) begin
        if (p_special[NS])
            r_y <= p_spec_y[NS];
        else
            r_y <= fp_round_pack(p_s[NS], p_e[NS],
                                  {q_all[QW-1:QW-26], (|q_all[QW-27:0]) | (r_all != 26'd0)});
    end

    assign y = r_y;
endmodule
