// IEEE 754 binary32 adder/subtractor: y = a + b (sub = 0) or a - b (sub = 1).
//
// Round to nearest, ties to even; subnormal inputs and results (gradual
// underflow); x + (-x) = +0; any NaN operand or inf - inf gives the
// canonical quiet NaN 0x7FC00000. Pipelined with latency `FP_ADD_LAT (4,
// see fp_latency.vh for the edge at which y appears), one operation per
// clock:
//   stage 0: the operands registered;
//   stage 1: classify, order the operands by magnitude, align the smaller
//            one (guard, round and sticky bits);
//   stage 2: add or subtract the significands, count leading zeros;
//   stage 3: normalise, round, pack.
`include "fp_latency.vh"

module fp_add (
    input  wire        clk,
    input  wire [31:0] a_in,
    input  wire [31:0] b_in,
    input  wire        sub_in,
    output wire [31:0] y
);
`include "fp_common.vh"

    // ---- stage 0: the operands registered (fp_latency.vh says why) ----
    reg [31:0] a;
    reg [31:0] b;
    reg sub;
    always @(posedge clk) begin
        a <= a_in;
        b <= b_in;
        sub <= sub_in;
    end

    // Each stage is one clocked block: its combinational logic is written
    // with blocking assignments to temporaries (assigned before use on every
    // path, so they synthesise to wires) and its results go to the stage's
    // registers. This also evaluates each stage once per clock in a
    // simulator.

    // ---- stage 1 ----
    reg               r1_special;  // a NaN, an infinity or a zero operand
    reg        [31:0] r1_spec_y;   // the result then
    reg               r1_s;        // sign of the larger operand
    reg signed [11:0] r1_e;        // its biased exponent
    reg        [23:0] r1_xm;       // its significand
    reg        [26:0] r1_yal;      // the smaller significand aligned, sticky in bit 0
    reg               r1_subtract; // the operands' effective signs differ

    // Operand classes (plain nets: cheap in a simulator, free in hardware).
    wire a_nan = (a[30:23] == 8'hFF) && (a[22:0] != 23'd0);
    wire b_nan = (b[30:23] == 8'hFF) && (b[22:0] != 23'd0);
    wire a_inf = (a[30:0] == 31'h7F80_0000);
    wire b_inf = (b[30:0] == 31'h7F80_0000);
    wire a_zero = (a[30:0] == 31'd0);
    wire b_zero = (b[30:0] == 31'd0);

    reg        [31:0] s1_be, s1_xw, s1_yw;
    reg        [35:0] s1_ux, s1_uy;
    reg        [11:0] s1_d;
    reg        [26:0] s1_sh;
    always @(posedge clk) begin
        s1_be = {b[31] ^ sub, b[30:0]};  // b with its effective sign
        // Magnitudes order like their encodings; x is the larger operand.
        if (b[30:0] > a[30:0]) begin
            s1_xw = s1_be;
            s1_yw = a;
        end else begin
            s1_xw = a;
            s1_yw = s1_be;
        end
        s1_ux = fp_unpack(s1_xw);
        s1_uy = fp_unpack(s1_yw);
        s1_d = s1_ux[35:24] - s1_uy[35:24];  // >= 0
        s1_sh = {s1_uy[23:0], 3'b000} >> s1_d;
        if (s1_d > 12'd26)
            r1_yal <= {26'd0, |s1_uy[23:0]};
        else
            r1_yal <= {s1_sh[26:1], s1_sh[0] | ((s1_sh << s1_d) != {s1_uy[23:0], 3'b000})};
        r1_s        <= s1_xw[31];
        r1_e        <= s1_ux[35:24];
        r1_xm       <= s1_ux[23:0];
        r1_subtract <= s1_xw[31] ^ s1_yw[31];

        r1_special <= 1'b1;
        if (a_nan || b_nan)
            r1_spec_y <= FP_QNAN;
        else if (a_inf && b_inf)
            r1_spec_y <= (a[31] == s1_be[31]) ? {a[31], 8'hFF, 23'd0} : FP_QNAN;
        else if (a_inf)
            r1_spec_y <= a;
        else if (b_inf)
            r1_spec_y <= s1_be;
        else if (a_zero && b_zero)
            r1_spec_y <= {a[31] & s1_be[31], 31'd0};
        else if (a_zero)
            r1_spec_y <= s1_be;
        else if (b_zero)
            r1_spec_y <= a;
        else begin
            r1_special <= 1'b0;
            r1_spec_y  <= 32'd0;
        end
    end

    // ---- stage 2 ----
    reg               r2_special;
    reg        [31:0] r2_spec_y;
    reg               r2_s;
    reg signed [11:0] r2_e;
    reg        [27:0] r2_sum;  // bit 27: carry of an addition
    reg        [ 4:0] r2_lz;

    reg        [27:0] s2_sum;
    always @(posedge clk) begin
        if (r1_subtract)
            s2_sum = {1'b0, r1_xm, 3'b000} - {1'b0, r1_yal};
        else
            s2_sum = {1'b0, r1_xm, 3'b000} + {1'b0, r1_yal};
        r2_sum     <= s2_sum;
        r2_lz      <= fp_lzc28(s2_sum);
        r2_special <= r1_special;
        r2_spec_y  <= r1_spec_y;
        r2_s       <= r1_s;
        r2_e       <= r1_e;
    end

    // ---- stage 3 ----
    reg        [31:0] r3_y;

    reg        [26:0] s3_m;
    reg signed [11:0] s3_e;
    always @(posedge clk) begin
        if (r2_sum[27]) begin
            s3_m = {r2_sum[27:2], r2_sum[1] | r2_sum[0]};
            s3_e = r2_e + 12'sd1;
        end else begin
            // r2_lz >= 1 here; a cancellation is exact, so no sticky is lost.
            s3_m = r2_sum[26:0] << (r2_lz - 5'd1);
            s3_e = r2_e - {7'd0, r2_lz} + 12'sd1;
        end
        if (r2_special)
            r3_y <= r2_spec_y;
        else if (r2_sum == 28'd0)
            r3_y <= 32'd0;  // exact cancellation: +0 under round to nearest
        else
            r3_y <= fp_round_pack(r2_s, s3_e, s3_m);
    end

    assign y = r3_y;
endmodule
