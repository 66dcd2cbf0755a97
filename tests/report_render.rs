//! The HTML reports rendered in a real browser (headless Chromium, when installed: Debian's
//! `chromium` package): at 1400 px wide, every SVG text (titles, tick labels, legends, joint
//! labels) lies inside its SVG and the page has no horizontal overflow — measured by the browser's
//! layout (getBoundingClientRect), not estimated. A screenshot is written next to each report
//! (`target/report-render/*.png`) for a person to look at. The reports are self-contained: no
//! script, no external resource. Skips visibly without Chromium.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn chromium() -> Option<String> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|exe| std::env::split_paths(&path).any(|d| d.join(exe).is_file()))
        .map(String::from)
}

fn run(cmd: &mut Command) -> (Option<i32>, String, String) {
    let o = cmd.output().unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

const WIDTH: u32 = 1400;

/// Appended to a COPY of the report: the browser measures every SVG text against its SVG.
const CHECK: &str = r#"<script>
(function () {
  var out = [], n = 0;
  document.querySelectorAll('svg').forEach(function (svg, si) {
    var s = svg.getBoundingClientRect();
    svg.querySelectorAll('text').forEach(function (t) {
      n++;
      var r = t.getBoundingClientRect();
      if (r.width > 0 && (r.left < s.left - 0.5 || r.right > s.right + 0.5 || r.top < s.top - 0.5 || r.bottom > s.bottom + 0.5)) {
        out.push('CLIPPED svg#' + si + ' "' + t.textContent + '" [' + Math.round(r.left - s.left) + ',' + Math.round(r.right - s.left) + '] of ' + Math.round(s.width));
      }
    });
  });
  var w = document.documentElement.scrollWidth;
  if (w > window.innerWidth) out.push('OVERFLOW page ' + w + ' px wide in a ' + window.innerWidth + ' px window');
  var p = document.createElement('pre');
  p.id = 'render-check';
  p.textContent = 'TEXTS ' + n + '\n' + out.join('\n');
  document.body.appendChild(p);
})();
</script>"#;

fn check_rendered(exe: &str, html: &Path, name: &str) {
    let page = std::fs::read_to_string(html).unwrap();
    // Self-contained: no script, no external resource (the SVG namespace is not a fetch).
    assert!(!page.contains("<script"), "{name}: the report has a script");
    let external = page.replace("http://www.w3.org/2000/svg", "");
    assert!(
        !external.contains("http://")
            && !external.contains("https://")
            && !external.contains("src="),
        "{name}: external resource"
    );
    // No tick label like "1e-1.4" (a fractional power of ten).
    assert!(!page.contains(">1e-") && !page.contains(">1e"), "{name}: a non-decade log tick");
    let out = root().join("target/report-render");
    std::fs::create_dir_all(&out).unwrap();
    let probe = out.join(format!("{name}-check.html"));
    std::fs::write(&probe, page.replace("</body>", &format!("{CHECK}</body>"))).unwrap();
    let size = format!("--window-size={WIDTH},3000");
    let (c, dom, err) = run(Command::new(exe)
        .args([
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--hide-scrollbars",
            &size,
            "--dump-dom",
        ])
        .arg(format!("file://{}", probe.display())));
    assert_eq!(c, Some(0), "{exe} --dump-dom failed: {err}");
    let check = dom
        .split("<pre id=\"render-check\">")
        .nth(1)
        .and_then(|s| s.split("</pre>").next())
        .unwrap_or_else(|| panic!("{name}: the check did not run: {dom}"));
    let texts: usize = check
        .lines()
        .next()
        .and_then(|l| l.strip_prefix("TEXTS "))
        .and_then(|n| n.trim().parse().ok())
        .unwrap_or(0);
    assert!(texts > 50, "{name}: only {texts} SVG texts measured");
    let problems: Vec<&str> = check.lines().skip(1).filter(|l| !l.trim().is_empty()).collect();
    assert!(problems.is_empty(), "{name} at {WIDTH} px:\n{}", problems.join("\n"));
    // The screenshot, for a person to look at.
    let png = out.join(format!("{name}.png"));
    let _ = std::fs::remove_file(&png);
    let (c, _, err) = run(Command::new(exe)
        .args(["--headless", "--disable-gpu", "--no-sandbox", "--hide-scrollbars", &size])
        .arg(format!("--screenshot={}", png.display()))
        .arg(format!("file://{}", html.display())));
    assert_eq!(c, Some(0), "{err}");
    let bytes = std::fs::read(&png).unwrap();
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    assert_eq!(w, WIDTH, "screenshot width");
    eprintln!(
        "{name}: {texts} SVG texts inside their charts at {WIDTH} px; screenshot {}",
        png.display()
    );
}

#[test]
fn fit_and_gap_reports_render_whole_at_1400_px() {
    let Some(exe) = chromium() else {
        eprintln!(
            "skipping: no chromium on PATH (apt-get install chromium); the reports were not rendered"
        );
        return;
    };
    let work = std::env::temp_dir().join(format!("modellint_render_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    let model = root().join("fixtures/gap/arm3.xml");
    let recs = work.join("rec");
    let bin = env!("CARGO_BIN_EXE_modellint");
    let (c, _, e) = run(Command::new(bin)
        .arg("synth")
        .arg(&model)
        .args([
            "--effects",
            "viscous_damping@elbow_pitch=0.4",
            "--episodes",
            "5",
            "--duration",
            "2",
            "--out",
        ])
        .arg(&recs));
    assert_eq!(c, Some(0), "{e}");
    let (c, _, e) = run(Command::new(bin)
        .arg("fit")
        .arg(&model)
        .arg(recs.join("episodes"))
        .args(["--effects", "viscous_damping", "--holdout", "2", "--report"])
        .arg(work.join("fit")));
    assert_eq!(c, Some(0), "{e}");
    let fit = work.join("fit/index.html");
    let page = std::fs::read_to_string(&fit).unwrap();
    for part in [
        "Missing physics",
        "viscous_damping",
        "±",
        "replayed before",
        "replayed after",
        "recorded",
        "Error per joint: before → after",
        "Power spectral density before → after",
    ] {
        assert!(page.contains(part), "fit report lacks {part}");
    }
    assert!(
        !work.join("fit/before").exists() && !work.join("fit/after").exists(),
        "one page, not two"
    );
    check_rendered(&exe, &fit, "fit");
    let (c, _, e) = run(Command::new(bin)
        .arg("gap")
        .arg(&model)
        .arg(recs.join("episodes"))
        .arg("--report")
        .arg(work.join("gap")));
    assert!(c == Some(0) || c == Some(1), "{e}");
    let gap = work.join("gap/index.html");
    let page = std::fs::read_to_string(&gap).unwrap();
    assert!(
        !page.contains(&recs.display().to_string().replace('&', "&amp;"))
            || page.contains("Recordings in"),
        "absolute paths in the episode table"
    );
    assert!(
        page.contains("<td style=\"text-align:left\">ep_00.csv</td>"),
        "episode names relative to their directory"
    );
    check_rendered(&exe, &gap, "gap");
    let _ = std::fs::remove_dir_all(&work);
}
