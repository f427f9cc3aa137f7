# Shared by bench/self_contacts_runs.sh and bench/commits_heavy_frames.sh (mawk or gawk, -F,
# given before each script's own program): the stats.csv files named on the command line, read
# by column name, scene_bench's heavy frames and the median of the frames' ratios.
#
# Per file (1, 2, ... in the order given) and frame f past 0: wall, solve, ccd, broad, narrow,
# halv (step_halvings), prox (proximity_impulses) and tests (vertex-face plus edge-edge); per
# file pen and warn (summed), stretch (largest) and last (the last frame). A column a file
# lacks (an earlier commit's stats.csv) reads as 0; has() says whether it was there.

function has(f, name) { return (f, name) in c }
function col(name) { return has(file, name) ? $c[file, name] : 0 }

# The most elementary tests of a frame of file f, and whether frame g of f is heavy: at least
# a tenth of that (scene_bench's rule).
function most_tests(f,   g, most) {
  most = 0
  for (g = 1; g <= last[f]; ++g) if (tests[f, g] > most) most = tests[f, g]
  return most
}
function heavy(f, g, most) { return most > 0 && tests[f, g] * 10 >= most }

# ratio[1..n] sorted in place; returns their median.
function sorted_median(ratio, n,   i, j, t) {
  for (i = 1; i <= n; ++i) for (j = i + 1; j <= n; ++j) if (ratio[j] < ratio[i]) { t = ratio[i]; ratio[i] = ratio[j]; ratio[j] = t }
  return n % 2 ? ratio[(n + 1) / 2] : (ratio[n / 2] + ratio[n / 2 + 1]) / 2
}

FNR == 1 { file++; for (i = 1; i <= NF; ++i) c[file, $i] = i; next }
{
  f = col("frame"); if (f == 0) next
  wall[file, f] = col("wall_ms"); solve[file, f] = col("solve_ms"); ccd[file, f] = col("ccd_ms")
  broad[file, f] = col("broad_ms"); narrow[file, f] = col("narrow_ms"); halv[file, f] = col("step_halvings")
  prox[file, f] = col("proximity_impulses"); tests[file, f] = col("vf_tests") + col("ee_tests")
  pen[file] += col("penetrations"); warn[file] += col("warnings")
  if (col("max_stretch") > stretch[file]) stretch[file] = col("max_stretch")
  if (f > last[file]) last[file] = f
}
