//! `modellint._native`: the Python package's bridge to the library. Each function takes the
//! command line the CLI would be given (parsed by the CLI's own clap definitions, so every
//! option, default and check is the CLI's), runs the same library function the CLI runs with
//! the GIL released, and returns the JSON the CLI prints with `--format json`. The typed
//! objects are made from that JSON in Python (python/modellint/).
//!
//! Errors are raised as `NativeError(kind, text, file, line, column)`: `kind` is `model` (the
//! model, spec or config could not be loaded: `file:line:col`), `run` (a recording, an option
//! value: one line, `file:line: message` for a recording) or `usage` (an unknown or malformed
//! option); python/modellint/errors.py turns them into typed exceptions.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};

use clap::Parser;
use modellint::cli::{Cli, Cmd};
use modellint::error::{CmdError, LoadError};
use modellint::fit::cmd_rotate::{rotate_run, rotation_json};
use modellint::fit::select::{Cancel, Progress, ProgressInfo, Selected};
use modellint::sink::{Silent, Sink};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;

create_exception!(_native, NativeError, PyException);

fn usage(msg: impl Into<String>) -> PyErr {
    NativeError::new_err(("usage", msg.into(), None::<String>, None::<usize>, None::<usize>))
}

fn load_error(e: LoadError) -> PyErr {
    NativeError::new_err((
        "model",
        e.message.clone(),
        Some(e.file.display().to_string()),
        e.line,
        e.column,
    ))
}

fn cmd_error(e: CmdError) -> PyErr {
    match e {
        CmdError::Load(e) => load_error(e),
        CmdError::Message(m) | CmdError::Said(m) => {
            NativeError::new_err(("run", m, None::<String>, None::<usize>, None::<usize>))
        }
    }
}

/// Parses `argv` (without the program name) with the CLI's definitions.
fn parse(argv: Vec<String>) -> PyResult<Cli> {
    let args = std::iter::once("modellint".to_string()).chain(argv);
    let cli = Cli::try_parse_from(args).map_err(|e| usage(e.render().to_string()))?;
    modellint::model::urdf_packages::set_packages(cli.packages());
    Ok(cli)
}

/// A Python progress callback, called with a dict; the first exception it raises is kept (and
/// raised when the work ends), the callback is not called again, and a fit is cancelled.
#[derive(Clone)]
struct Callback {
    f: Arc<Py<PyAny>>,
    error: Arc<Mutex<Option<PyErr>>>,
    cancel: Option<Cancel>,
}

impl Callback {
    fn new(f: Py<PyAny>) -> Self {
        Callback { f: Arc::new(f), error: Arc::new(Mutex::new(None)), cancel: None }
    }
    fn call(&self, fill: impl FnOnce(&Bound<'_, PyDict>) -> PyResult<()>) {
        let Ok(mut err) = self.error.lock() else { return };
        if err.is_some() {
            return;
        }
        Python::attach(|py| {
            let d = PyDict::new(py);
            if let Err(e) = fill(&d).and_then(|_| self.f.call1(py, (d,))) {
                *err = Some(e);
                if let Some(c) = &self.cancel {
                    c.set();
                }
            }
        });
    }
    fn raised(&self) -> PyResult<()> {
        match self.error.lock().ok().and_then(|mut e| e.take()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// `gap`'s replay counter to the callback; everything else is in the result.
struct ReplaySink(Option<Callback>);

impl Sink for ReplaySink {
    fn warning(&self, _: &str) {}
    fn note(&self, _: &str) {}
    fn note_always(&self, _: &str) {}
    fn said(&self, _: &str) {}
    fn replayed(&self, k: usize, total: usize) {
        if let Some(c) = &self.0 {
            c.call(|d| {
                d.set_item("phase", "replay")?;
                d.set_item("done", k)?;
                d.set_item("total", total)
            });
        }
    }
}

/// `modellint MODEL [options] --format json`: the findings JSON of one model.
#[pyfunction]
fn lint(py: Python<'_>, argv: Vec<String>) -> PyResult<String> {
    let cli = parse(argv)?;
    if cli.cmd.is_some() {
        return Err(usage("lint takes a model path and lint options"));
    }
    let a = cli.check;
    let [model] = a.models.as_slice() else {
        return Err(usage("lint takes exactly one model path"));
    };
    let input = modellint::lint::LintInput {
        model: model.clone(),
        spec: a.spec.clone(),
        config: a.config.clone(),
        select: a.select.clone(),
        ignore: a.ignore.clone(),
    };
    let cache_dir = if a.no_cache {
        None
    } else {
        a.cache_dir.clone().or_else(modellint::model::cache::default_dir)
    };
    py.detach(move || modellint::lint::lint_json(&input, !a.no_probe, cache_dir.as_deref()))
        .map_err(load_error)
}

/// `modellint gap MODEL RECORDINGS… [options] --format json`: the gap report JSON.
#[pyfunction]
#[pyo3(signature = (argv, progress=None))]
fn gap(py: Python<'_>, argv: Vec<String>, progress: Option<Py<PyAny>>) -> PyResult<String> {
    let Some(Cmd::Gap(g)) = parse(argv)?.cmd else {
        return Err(usage("expected `gap` and its arguments"));
    };
    let args = g.into_args();
    let cb = progress.map(Callback::new);
    let sink = ReplaySink(cb.clone());
    let report = py.detach(move || modellint::sim2real::cmd::gap(&args, &sink));
    if let Some(c) = &cb {
        c.raised()?;
    }
    let report = report.map_err(cmd_error)?;
    modellint::sim2real::cmd::gap_json(&report)
        .and_then(|v| serde_json::to_string_pretty(&v))
        .map(|s| s + "\n")
        .map_err(|e| usage(format!("cannot serialise the report: {e}")))
}

/// What a fit kept, for `FitResult.write_model` after the fit.
#[pyclass(frozen)]
struct Fitted {
    model: PathBuf,
    spec: Option<PathBuf>,
    selected: Vec<Selected>,
}

#[pymethods]
impl Fitted {
    /// Writes the model with the MuJoCo-expressible fitted values to `path` (as
    /// `fit --write-model`); returns the notes (which files, what could not be written).
    fn write_model(&self, py: Python<'_>, path: PathBuf) -> PyResult<Vec<String>> {
        let (model, spec, selected) = (self.model.clone(), self.spec.clone(), &self.selected);
        py.detach(|| {
            let loaded = modellint::lint::load_for_api(&model, spec).map_err(CmdError::Load)?;
            modellint::fit::cmd::write_model(&model, &loaded.robot, selected, &path, &Silent)
        })
        .map_err(cmd_error)
    }
}

/// `modellint fit MODEL RECORDINGS… [options] --format json`: the fit JSON, and what was kept
/// (for writing the model later).
#[pyfunction]
#[pyo3(signature = (argv, progress=None))]
fn fit(
    py: Python<'_>,
    argv: Vec<String>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, Fitted)> {
    let Some(Cmd::Fit(f)) = parse(argv)?.cmd else {
        return Err(usage("expected `fit` and its arguments"));
    };
    let args = f.into_args();
    let cancel = Cancel::default();
    let cb = progress.map(|f| Callback { cancel: Some(cancel.clone()), ..Callback::new(f) });
    let hook = cb.clone().map(|c| {
        let start = Instant::now();
        Progress(Arc::new(move |p: &ProgressInfo| {
            c.call(|d| {
                d.set_item("phase", p.phase.to_string())?;
                d.set_item("round", p.round + 1)?;
                d.set_item("candidate", p.candidate.clone())?;
                d.set_item("simulations", p.simulations)?;
                d.set_item("rollouts", p.rollouts)?;
                d.set_item("elapsed_s", start.elapsed().as_secs_f64())
            })
        }))
    });
    let flag = cancel.clone();
    let run = interruptible(py, cancel, move || {
        let mut p = modellint::fit::cmd::prepare(&args, &Silent)?;
        p.opts.cancel = Some(flag);
        if let Some(key) = p.rotate_by.clone() {
            // `holdout_by="KEY"`: the rotation's JSON; nothing kept to write.
            let mut fold_progress = |_: Option<&str>| hook.clone();
            let r = rotate_run(&p, &key, &args, &Silent, &mut fold_progress)?;
            let json = serde_json::to_string_pretty(&rotation_json(&r))
                .map_err(|e| CmdError::Message(format!("cannot serialise the result: {e}")))?;
            let kept = Fitted { model: args.model, spec: args.spec, selected: vec![] };
            return Ok((json + "\n", kept));
        }
        let r = modellint::fit::cmd::fit_once(&args, &p, &Silent, hook, &|| {})?;
        let json = serde_json::to_string_pretty(&modellint::fit::cmd::fit_json(&r))
            .map_err(|e| CmdError::Message(format!("cannot serialise the result: {e}")))?;
        Ok((json + "\n", Fitted { model: args.model, spec: args.spec, selected: r.out.selected }))
    })?;
    if let Some(c) = &cb {
        c.raised()?;
    }
    run.map_err(cmd_error)
}

/// How often a long run checks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(100);

/// Runs `work` on a thread of its own while this (the calling, Python's main) thread, without
/// the GIL, checks Python's signals every [`SIGNAL_POLL`]: on KeyboardInterrupt (or any
/// exception a signal handler raises) it sets `cancel`, which the fit core polls before each
/// replay, waits for the work to wind down and raises the exception. Python runs signal
/// handlers only on its main thread, and only when that thread asks: the work's own threads
/// (the progress callback is called from them) cannot see a Ctrl-C.
fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    cancel: Cancel,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    let (tx, rx) = mpsc::channel();
    let worker = std::thread::spawn(move || {
        let _ = tx.send(work());
    });
    let mut rx = rx;
    loop {
        let (got, back) = py.detach(move || (rx.recv_timeout(SIGNAL_POLL), rx));
        rx = back;
        match got {
            Ok(v) => {
                let _ = worker.join();
                return Ok(v);
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    cancel.set();
                    py.detach(move || {
                        let _ = rx.recv();
                        let _ = worker.join();
                    });
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                let why = match worker.join() {
                    Err(p) => p
                        .downcast_ref::<&str>()
                        .map(|s| s.to_string())
                        .or_else(|| p.downcast_ref::<String>().cloned())
                        .unwrap_or_default(),
                    Ok(()) => String::new(),
                };
                return Err(NativeError::new_err((
                    "run",
                    format!("internal error: the fit stopped without a result ({why})"),
                    None::<String>,
                    None::<usize>,
                    None::<usize>,
                )));
            }
        }
    }
}

#[pymodule]
#[pyo3(name = "_native")]
fn modellint_native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    modellint::model::mj::silence_warnings();
    m.add("NativeError", m.py().get_type::<NativeError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(lint, m)?)?;
    m.add_function(wrap_pyfunction!(gap, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_class::<Fitted>()?;
    Ok(())
}
