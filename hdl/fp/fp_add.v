// IEEE 754 binary32 adder/subtractor: y = a + b (sub = 0) or a - b (sub = 1).
//
// Round to nearest, ties to even; subnormal inputs and results (gradual
// underflow); x + (-x) = +0; any NaN operand or inf - inf gives the
// canonical quiet NaN 0x7FC00000. Pipelined with latency `FP_ADD_LAT (3,
// see fp_latency.vh for the edge at which y appears), one operation per
// clock. Unlike the multiplier and the divider it does not register its
// operands first: the core feeds it only from registers (fp_latency.vh).
//   stage 1: classify, order the operands by magnitude, align the smaller
//            one (guard, round and sticky bits);
//   stage 2: add or subtract the significands, count leading zeros;
//   stage 3: normalise, round, pack.
//
// Subnormals need no unpacking here: a subnormal is its fraction with a
// hidden 0 at exponent 1, so the significands are aligned by the encoded
// exponents as they are. A sum is normalised by at most its leading zeros
// and never below exponent 1: a result under the normal range is then its
// subnormal encoding as it stands, and exact (both operands are multiples
// of 2^-149), so no right shift into the subnormal range is needed.
`include "fp_latency.vh"

module fp_add (
    input  wire        clk,
    input  wire [31:0] a,
    input  wire [31:0] b,
    input  wire        sub,
    output wire [31:0] y
);
`include "fp_common.vh"

    // Each stage is one clocked block: its combinational logic is written
    // with blocking assignments to temporaries (assigned before use on every
    // path, so they synthesise to wires) and its results go to the stage's
    // registers. This also evaluates each stage once per clock in a
    // simulator.

    // Operand classes (plain nets: cheap in a simulator, free in hardware).
    wire a_nan = (a[30:23] == 8'hFF) && (a[22:0] != 23'd0);
    wire b_nan = (b[30:23] == 8'hFF) && (b[22:0] != 23'd0);
    wire a_inf = (a[30:0] == 31'h7F80_0000);
    wire b_inf = (b[30:0] == 31'h7F80_0000);
    wire a_zero = (a[30:0] == 31'd0);
    wire b_zero = (b[30:0] == 31'd0);

    // Each operand's exponent (a subnormal's is 1), significand (hidden bit
    // included) and trailing zeros, found beside the ordering compare; the
    // exponent difference both ways, so that the compare only chooses.
    wire [7:0]  ea = fp_exp1(a);
    wire [7:0]  eb = fp_exp1(b);
    wire [23:0] ma = fp_sig24(a);
    wire [23:0] mb = fp_sig24(b);
    wire [4:0]  tza = fp_tzc24(ma);
    wire [4:0]  tzb = fp_tzc24(mb);
    wire [7:0]  dab = ea - eb;
    wire [7:0]  dba = eb - ea;

    // ---- stage 1 ----
    reg               r1_special;  // a NaN, an infinity or a zero operand
    reg        [31:0] r1_spec_y;   // the result then
    reg               r1_s;        // sign of the larger operand
    reg        [7:0]  r1_e;        // its exponent (>= 1)
    reg        [23:0] r1_xm;       // its significand
    reg        [26:0] r1_yal;      // the smaller significand aligned, sticky in bit 0
    reg               r1_subtract; // the operands' effective signs differ

    reg               s1_bs;       // b's effective sign
    reg               s1_swap;     // b is the larger magnitude
    reg        [7:0]  s1_d;        // exponent difference, >= 0
    reg        [23:0] s1_ym;
    reg        [4:0]  s1_tz;
    always @(posedge clk) begin
        s1_bs = b[31] ^ sub;
        // Magnitudes order like their encodings; x is the larger operand.
        s1_swap = b[30:0] > a[30:0];
        s1_d  = s1_swap ? dba : dab;
        s1_ym = s1_swap ? ma : mb;
        s1_tz = s1_swap ? tza : tzb;
        // Bits shifted out of {ym, 000} are nonzero when its trailing zeros
        // (tz + 3) are fewer than the shift d.
        r1_yal <= ({s1_ym, 3'b000} >> s1_d)
                  | {26'd0, ({3'd0, s1_tz} + 8'd3) < s1_d};
        r1_s        <= s1_swap ? s1_bs : a[31];
        r1_e        <= s1_swap ? eb : ea;
        r1_xm       <= s1_swap ? mb : ma;
        r1_subtract <= a[31] ^ s1_bs;

        r1_special <= 1'b1;
        if (a_nan || b_nan)
            r1_spec_y <= FP_QNAN;
        else if (a_inf && b_inf)
            r1_spec_y <= (a[31] == s1_bs) ? {a[31], 8'hFF, 23'd0} : FP_QNAN;
        else if (a_inf)
            r1_spec_y <= a;
        else if (b_inf)
            r1_spec_y <= {s1_bs, b[30:0]};
        else if (a_zero && b_zero)
            r1_spec_y <= {a[31] & s1_bs, 31'd0};
        else if (a_zero)
            r1_spec_y <= {s1_bs, b[30:0]};
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
    reg        [7:0]  r2_e;
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

    reg        [26:0] s3_m;   // s3_m[26] = 1, or 0 for a subnormal result
    reg        [8:0]  s3_e;   // exponent of s3_m[26], >= 1
    reg        [4:0]  s3_sh;
    reg               s3_inc;
    reg        [30:0] s3_mag;
    always @(posedge clk) begin
        s3_sh = 5'd0;
        if (r2_sum[27]) begin
            s3_m = {r2_sum[27:2], r2_sum[1] | r2_sum[0]};
            s3_e = {1'b0, r2_e} + 9'd1;
        end else begin
            // r2_lz >= 1 here. The shift stops at exponent 1 (a subnormal
            // result); a shift of more than one bit follows a cancellation,
            // which is exact, so no sticky bit is lost.
            s3_sh = ({3'd0, r2_lz} - 8'd1 < r2_e - 8'd1) ? r2_lz - 5'd1 : r2_e[4:0] - 5'd1;
            s3_m = r2_sum[26:0] << s3_sh;
            s3_e = {1'b0, r2_e} - {4'd0, s3_sh};
        end
        s3_inc = s3_m[2] & (s3_m[3] | s3_m[1] | s3_m[0]);
        // A carry out of the fraction moves a subnormal to the smallest
        // normal, and the largest finite to infinity.
        s3_mag = {s3_m[26] ? s3_e[7:0] : 8'd0, s3_m[25:3]} + {30'd0, s3_inc};
        if (r2_special)
            r3_y <= r2_spec_y;
        else if (r2_sum == 28'd0)
            r3_y <= 32'd0;  // exact cancellation: +0 under round to nearest
        else if (s3_e >= 9'd255)
            r3_y <= {r2_s, 8'hFF, 23'd0};
        else
            r3_y <= {r2_s, s3_mag};
    end

    assign y = r3_y;
endmodule
