// The run's charts against time (volume error, step size, Newton iterations per step), on a
// logarithmic scale where every value is positive, with the current frame's time as a line.
const PAD = { left: 46, right: 8, top: 8, bottom: 18 };

function extent(values, log) {
  let lo = Infinity, hi = -Infinity;
  for (const v of values) if (v !== null && (!log || v > 0)) (lo = Math.min(lo, v)), (hi = Math.max(hi, v));
  if (!isFinite(lo)) return null;
  if (log) return lo === hi ? [Math.log10(lo) - 1, Math.log10(hi) + 1] : [Math.log10(lo), Math.log10(hi)];
  return lo === hi ? [lo - 1, hi + 1] : [Math.min(lo, 0), hi];
}

export function timeAt(canvas, x, timeEnd) {
  const w = canvas.width - PAD.left - PAD.right;
  return Math.max(0, Math.min(1, (x - PAD.left) / w)) * timeEnd;
}

export function drawChart(canvas, series, time, timeEnd) {
  const g = canvas.getContext("2d");
  const W = canvas.width, H = canvas.height, w = W - PAD.left - PAD.right, h = H - PAD.top - PAD.bottom;
  g.clearRect(0, 0, W, H);
  g.font = "10px system-ui, sans-serif";
  g.fillStyle = "#777";
  if (!series || !series.y.some((v) => v !== null)) {
    g.fillText("not recorded by this run", PAD.left, H / 2);
    return;
  }
  // Logarithmic where no value is negative and the positive ones span more than a decade (zeros,
  // such as a step size before the first step, are then left out).
  const positive = series.y.filter((v) => v !== null && v > 0);
  const log = series.y.every((v) => v === null || v >= 0) && positive.length > 0 &&
    Math.max(...positive) > 10 * Math.min(...positive);
  const [lo, hi] = extent(series.y, log);
  const X = (t) => PAD.left + (timeEnd > 0 ? t / timeEnd : 0) * w;
  const Y = (v) => PAD.top + h - (((log ? Math.log10(v) : v) - lo) / (hi - lo)) * h;
  g.strokeStyle = "#ccc";
  g.strokeRect(PAD.left, PAD.top, w, h);
  g.fillText(log ? `1e${hi.toFixed(1)}` : hi.toPrecision(3), 2, PAD.top + 8);
  g.fillText(log ? `1e${lo.toFixed(1)}` : lo.toPrecision(3), 2, PAD.top + h);
  g.fillText(`${timeEnd.toPrecision(3)} s`, W - PAD.right - 40, H - 4);
  g.strokeStyle = "#3b6ea5";
  g.beginPath();
  let pen = false;
  series.t.forEach((t, i) => {
    const v = series.y[i];
    if (v === null || (log && !(v > 0))) return void (pen = false);
    pen ? g.lineTo(X(t), Y(v)) : g.moveTo(X(t), Y(v));
    pen = true;
  });
  g.stroke();
  g.strokeStyle = "#c0392b";
  g.beginPath();
  g.moveTo(X(time), PAD.top);
  g.lineTo(X(time), PAD.top + h);
  g.stroke();
}
