//! Headless Chromium with WebGPU, driven through the DevTools protocol over a WebSocket.
//!
//! Chromium is started with `--remote-debugging-port=0` and a fresh profile; it writes the
//! port it chose to `DevToolsActivePort` in that profile. We attach to the page target with a
//! flattened session and evaluate JavaScript in it. The flags expose WebGPU in headless Chromium:
//! WebGPU over SwiftShader's Vulkan, without which the WebGPU canvas is missing from screenshots.

use std::collections::VecDeque;
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context as _, bail};
use serde_json::{Value, json};
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// The running browser; killed on drop.
#[derive(Debug)]
pub struct Browser {
    child: Child,
    pub ws_url: String,
}

pub fn find_chromium(explicit: Option<PathBuf>) -> anyhow::Result<PathBuf> {
    if let Some(p) = explicit {
        return Ok(p);
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    for name in ["chromium", "chromium-browser", "google-chrome", "google-chrome-stable"] {
        if let Some(p) = std::env::split_paths(&path).map(|d| d.join(name)).find(|p| p.is_file()) {
            return Ok(p);
        }
    }
    bail!("no Chromium found on PATH (apt-get install chromium), or pass --chromium")
}

impl Browser {
    pub fn launch(binary: &Path, profile: &Path, timeout: Duration) -> anyhow::Result<Browser> {
        if profile.exists() {
            std::fs::remove_dir_all(profile)?;
        }
        std::fs::create_dir_all(profile)?;
        let log = std::fs::File::create(profile.with_extension("log"))?;
        let child = Command::new(binary)
            .args([
                "--headless",
                "--no-sandbox",
                "--enable-unsafe-webgpu",
                "--enable-features=Vulkan",
                "--use-angle=vulkan",
                "--use-vulkan=swiftshader",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--remote-debugging-address=127.0.0.1",
                "--remote-debugging-port=0",
                "--window-size=1280,800",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(log.try_clone()?)
            .stderr(log)
            .spawn()
            .with_context(|| format!("starting {}", binary.display()))?;
        let mut browser = Browser { child, ws_url: String::new() };
        let port_file = profile.join("DevToolsActivePort");
        let started = Instant::now();
        loop {
            if let Ok(text) = std::fs::read_to_string(&port_file) {
                let mut lines = text.lines();
                if let (Some(port), Some(path)) = (lines.next(), lines.next()) {
                    browser.ws_url = format!("ws://127.0.0.1:{}{}", port.trim(), path.trim());
                    return Ok(browser);
                }
            }
            if let Some(status) = browser.child.try_wait()? {
                bail!(
                    "{} exited ({status}) before opening DevTools; see {}",
                    binary.display(),
                    profile.with_extension("log").display()
                );
            }
            if started.elapsed() > timeout {
                bail!("{} did not open DevTools within {timeout:?}", binary.display());
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A DevTools connection attached to one page.
#[derive(Debug)]
pub struct Page {
    ws: WebSocket<MaybeTlsStream<TcpStream>>,
    next_id: u64,
    session: String,
    /// Console messages and exceptions seen so far (for failure reports).
    pub console: VecDeque<String>,
}

impl Page {
    /// Connects to the browser and attaches to its first page.
    pub fn attach(browser: &Browser) -> anyhow::Result<Page> {
        let (ws, _) = tungstenite::connect(&browser.ws_url).context("connecting to Chromium's DevTools")?;
        if let MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_secs(5)))?;
        }
        let mut page = Page { ws, next_id: 0, session: String::new(), console: VecDeque::new() };
        let targets = page.call("Target.getTargets", json!({}), false)?;
        let id = targets["targetInfos"]
            .as_array()
            .and_then(|t| t.iter().find(|t| t["type"] == "page"))
            .and_then(|t| t["targetId"].as_str())
            .context("Chromium has no page target")?
            .to_string();
        let attached = page.call("Target.attachToTarget", json!({"targetId": id, "flatten": true}), false)?;
        page.session = attached["sessionId"].as_str().context("no DevTools session id")?.to_string();
        page.call("Runtime.enable", json!({}), true)?;
        page.call("Page.enable", json!({}), true)?;
        Ok(page)
    }

    /// Sends a command (to the page's session when `session`) and waits for its result.
    pub fn call(&mut self, method: &str, params: Value, session: bool) -> anyhow::Result<Value> {
        self.next_id += 1;
        let id = self.next_id;
        let mut msg = json!({"id": id, "method": method, "params": params});
        if session {
            msg["sessionId"] = json!(self.session);
        }
        self.ws.send(Message::text(msg.to_string()))?;
        let started = Instant::now();
        loop {
            let m = match self.ws.read() {
                Ok(m) => m,
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) =>
                {
                    if started.elapsed() > Duration::from_secs(600) {
                        bail!("DevTools gave no answer to {method} in 10 minutes");
                    }
                    continue;
                }
                Err(e) => return Err(e).context("reading from DevTools"),
            };
            let Message::Text(text) = m else { continue };
            let v: Value = serde_json::from_str(text.as_str())?;
            if v["id"] == id {
                if let Some(e) = v.get("error") {
                    bail!("DevTools {method} failed: {e}");
                }
                return Ok(v["result"].clone());
            }
            self.note_event(&v);
        }
    }

    fn note_event(&mut self, v: &Value) {
        let line = match v["method"].as_str() {
            Some("Runtime.consoleAPICalled") => {
                let args: Vec<String> = v["params"]["args"]
                    .as_array()
                    .map(|a| {
                        a.iter()
                            .map(|x| x["value"].as_str().map_or_else(|| x["value"].to_string(), str::to_string))
                            .collect()
                    })
                    .unwrap_or_default();
                format!("console.{}: {}", v["params"]["type"].as_str().unwrap_or("log"), args.join(" "))
            }
            Some("Runtime.exceptionThrown") => {
                let d = &v["params"]["exceptionDetails"];
                format!(
                    "exception: {} {}",
                    d["text"].as_str().unwrap_or(""),
                    d["exception"]["description"].as_str().unwrap_or("")
                )
            }
            _ => return,
        };
        self.console.push_back(line);
        if self.console.len() > 200 {
            self.console.pop_front();
        }
    }

    /// Evaluates a JavaScript expression (awaiting a promise) and returns its value as JSON.
    pub fn eval(&mut self, expr: &str) -> anyhow::Result<Value> {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expr, "awaitPromise": true, "returnByValue": true}),
            true,
        )?;
        if let Some(e) = r.get("exceptionDetails") {
            let text = e["exception"]["description"].as_str().or(e["text"].as_str()).unwrap_or("?");
            bail!("JavaScript `{}` threw: {text}", expr.chars().take(120).collect::<String>());
        }
        Ok(r["result"]["value"].clone())
    }

    /// Polls `expr` until it yields something other than null/false/undefined.
    pub fn wait_for(&mut self, what: &str, expr: &str, timeout: Duration) -> anyhow::Result<Value> {
        let started = Instant::now();
        loop {
            let v = self.eval(expr)?;
            if !(v.is_null() || v == Value::Bool(false)) {
                return Ok(v);
            }
            if started.elapsed() > timeout {
                bail!(
                    "timed out after {timeout:?} waiting for {what}; last console lines:\n{}",
                    self.console.iter().rev().take(15).rev().cloned().collect::<Vec<_>>().join("\n")
                );
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    }

    /// A PNG screenshot of the page.
    pub fn screenshot(&mut self) -> anyhow::Result<Vec<u8>> {
        use base64::Engine as _;
        let r = self.call("Page.captureScreenshot", json!({"format": "png"}), true)?;
        let data = r["data"].as_str().context("no screenshot data")?;
        Ok(base64::engine::general_purpose::STANDARD.decode(data)?)
    }
}
