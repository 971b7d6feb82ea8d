//! A small synchronous WebDriver client for the browser tests (tests/browser.rs): Debian's
//! chromium, headless, driven by its chromedriver on a loopback port.
//!
//! Why not `fantoccini` or `thirtyfour`: fantoccini without TLS brought 77 crates (tokio,
//! hyper, the webdriver crate and ICU's Unicode tables among them) whose build took 4 min 05 s
//! of this 2-core machine (`cargo build --tests`, measured 2026-11-29), a third of CI's
//! 12-minute budget, for a test that needs a dozen JSON requests over HTTP/1.1 to localhost.
//! This client is those requests (serde_json is already a dependency).

use std::io::{Read as _, Write as _};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

/// The W3C element reference key.
pub const ELEMENT: &str = "element-6066-11e4-a52e-4f735466cecf";

/// A chromium session under its chromedriver; both end when it drops.
pub struct Browser {
    driver: Child,
    port: u16,
    /// The driver's URL base (`--url-base`).
    base: String,
    session: String,
    profile: PathBuf,
}

/// Debian's chromium: the real binary (its /usr/bin/chromium is a wrapper script).
fn chromium() -> Option<&'static str> {
    ["/usr/lib/chromium/chromium", "/usr/bin/chromium"]
        .into_iter()
        .find(|p| Path::new(p).exists())
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free loopback port")
}

/// One HTTP/1.1 exchange with the driver: the status and the body as JSON.
fn http(
    port: u16,
    method: &str,
    path: &str,
    body: Option<&Value>,
) -> std::io::Result<(u16, Value)> {
    let mut stream = TcpStream::connect(("127.0.0.1", port))?;
    stream.set_read_timeout(Some(Duration::from_secs(120)))?;
    let body = body.map(|b| b.to_string()).unwrap_or_default();
    let request = format!(
        "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nContent-Type: application/json; \
         charset=utf-8\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(request.as_bytes())?;
    // chromedriver keeps the connection open whatever the request says: read the headers, then
    // the body's Content-Length (or its chunks), not to the end of the stream.
    let bad = |what: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, what.to_string());
    let mut raw = Vec::new();
    let mut buf = [0u8; 65536];
    let split = loop {
        if let Some(p) = raw.windows(4).position(|w| w == b"\r\n\r\n") {
            break p;
        }
        let n = stream.read(&mut buf)?;
        if n == 0 {
            return Err(bad(
                "the driver closed the connection before its headers ended",
            ));
        }
        raw.extend_from_slice(&buf[..n]);
    };
    let head = String::from_utf8_lossy(&raw[..split]).to_string();
    let status: u16 = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| bad("no status"))?;
    let header = |name: &str| {
        head.lines().find_map(|l| {
            let (k, v) = l.split_once(':')?;
            k.trim()
                .eq_ignore_ascii_case(name)
                .then(|| v.trim().to_string())
        })
    };
    let mut content = raw[split + 4..].to_vec();
    let chunked = header("transfer-encoding").is_some_and(|v| v.eq_ignore_ascii_case("chunked"));
    let length: Option<usize> = header("content-length").and_then(|v| v.parse().ok());
    loop {
        let done = match (chunked, length) {
            (true, _) => dechunk(&content).is_some(),
            (false, Some(n)) => content.len() >= n,
            (false, None) => {
                return Err(bad(&format!(
                    "{method} {path}: a response with neither Content-Length nor chunks"
                )))
            }
        };
        if done {
            break;
        }
        let n = stream.read(&mut buf)?;
        if n == 0 {
            break;
        }
        content.extend_from_slice(&buf[..n]);
    }
    if chunked {
        content = dechunk(&content).ok_or_else(|| bad("bad chunked body"))?;
    } else if let Some(n) = length {
        content.truncate(n);
    }
    let value = if content.is_empty() {
        Value::Null
    } else {
        serde_json::from_slice(&content).map_err(|e| bad(&format!("{e}")))?
    };
    Ok((status, value))
}

fn dechunk(mut data: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    loop {
        let line = data.windows(2).position(|w| w == b"\r\n")?;
        let size_text = std::str::from_utf8(&data[..line]).ok()?;
        let size = usize::from_str_radix(size_text.split(';').next()?.trim(), 16).ok()?;
        data = &data[line + 2..];
        if size == 0 {
            return Some(out);
        }
        out.extend_from_slice(data.get(..size)?);
        data = data.get(size + 2..)?;
    }
}

impl Browser {
    /// Starts chromedriver and a headless chromium whose page is `width` x `height` CSS pixels
    /// at one device pixel each. Without them: a panic saying what to install where the
    /// browser is required (scripts/test.sh, which installs them, sets IRAD_REQUIRE_BROWSER;
    /// CI), else None and a note (scripts/gpu-check.sh on a machine with no network).
    pub fn start(width: u32, height: u32) -> Option<Browser> {
        let found = chromium().filter(|_| {
            Command::new("chromedriver")
                .arg("--version")
                .stdout(Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        });
        let Some(chromium) = found else {
            let install = "chromium or chromedriver not found: `bash scripts/setup.sh --browser` \
                           installs Debian's chromium and chromium-driver";
            let required = std::env::var("IRAD_REQUIRE_BROWSER")
                .is_ok_and(|v| !v.is_empty() && v != "0")
                || super::under_ci();
            assert!(!required, "{install}");
            eprintln!("note: {install}; skipping the browser checks");
            return None;
        };
        for _ in 0..3 {
            if let Some(browser) = Browser::start_on(chromium, free_port(), width, height) {
                return Some(browser);
            }
        }
        panic!("chromedriver did not start on three ports");
    }

    /// Chromedriver on `port` (None where it exits first: another took the port), then the
    /// session. Its URLs start with a base of this process and port, so that no other
    /// driver on a reused port can answer for it.
    fn start_on(chromium: &str, port: u16, width: u32, height: u32) -> Option<Browser> {
        use std::os::unix::process::CommandExt as _;
        let base = format!("/irad-{}-{port}", std::process::id());
        // Its own process group, so that Drop ends chromium with it (an interrupted test run
        // leaves both running: `pkill chromedriver` ends them).
        let mut driver = Command::new("chromedriver")
            .arg(format!("--port={port}"))
            .arg(format!("--url-base={base}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .process_group(0)
            .spawn()
            .expect("chromedriver starts");
        let profile =
            std::env::temp_dir().join(format!("irad-chromium-{}-{port}", std::process::id()));
        let start = Instant::now();
        loop {
            // Exited (and reaped): nothing of it to end, so no Browser (whose Drop would
            // signal a process group that may since be another's).
            if driver.try_wait().ok().flatten().is_some() {
                return None;
            }
            match http(port, "GET", &format!("{base}/status"), None) {
                Ok((200, v)) if v["value"]["ready"] == json!(true) => break,
                _ if start.elapsed() > Duration::from_secs(30) => {
                    panic!("chromedriver on port {port} not ready after 30 s")
                }
                _ => std::thread::sleep(Duration::from_millis(50)),
            }
        }
        let mut browser = Browser {
            driver,
            port,
            base,
            session: String::new(),
            profile,
        };
        let args = [
            "--headless=new".to_string(),
            "--no-sandbox".into(),
            "--disable-gpu".into(),
            "--disable-dev-shm-usage".into(),
            "--no-first-run".into(),
            "--disable-background-networking".into(),
            "--disable-component-update".into(),
            "--disable-sync".into(),
            "--disable-quic".into(),
            format!("--user-data-dir={}", browser.profile.display()),
            format!("--window-size={},{}", width + 100, height + 200),
        ];
        let capabilities = json!({"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": {"binary": chromium, "args": args},
            "goog:loggingPrefs": {"browser": "ALL"},
        }}});
        let (status, v) = http(
            port,
            "POST",
            &format!("{}/session", browser.base),
            Some(&capabilities),
        )
        .expect("chromedriver answers");
        assert_eq!(status, 200, "new session: {v}");
        browser.session = v["value"]["sessionId"]
            .as_str()
            .expect("a session id")
            .to_string();
        // The page's size exactly, whatever the window's decorations.
        browser.cmd(
            "POST",
            "/goog/cdp/execute",
            json!({"cmd": "Emulation.setDeviceMetricsOverride", "params": {
                "width": width, "height": height, "deviceScaleFactor": 1, "mobile": false}}),
        );
        Some(browser)
    }

    /// A command of the session (`path` after /session/ID); panics with the driver's error.
    pub fn cmd(&self, method: &str, path: &str, body: Value) -> Value {
        let body = match method {
            "POST" => Some(&body),
            _ => None,
        };
        let url = format!("{}/session/{}{path}", self.base, self.session);
        let (status, v) =
            http(self.port, method, &url, body).unwrap_or_else(|e| panic!("{method} {path}: {e}"));
        assert_eq!(status, 200, "{method} {path}: {v}");
        v["value"].clone()
    }

    pub fn open(&self, file: &Path) {
        let url = format!(
            "file://{}",
            file.canonicalize().expect("the page exists").display()
        );
        self.cmd("POST", "/url", json!({ "url": url }));
    }

    /// The first element matching `css`.
    pub fn find(&self, css: &str) -> String {
        let v = self.cmd(
            "POST",
            "/element",
            json!({"using": "css selector", "value": css}),
        );
        v[ELEMENT].as_str().expect("an element").to_string()
    }

    pub fn click(&self, element: &str) {
        self.cmd("POST", &format!("/element/{element}/click"), json!({}));
    }

    /// The value of `script` (a function body; `arguments` are `args`).
    pub fn js(&self, script: &str, args: Value) -> Value {
        self.cmd(
            "POST",
            "/execute/sync",
            json!({"script": script, "args": args}),
        )
    }

    /// `element`'s rectangle in CSS pixels of the viewport (where pointer actions and the
    /// screenshot's pixels are; WebDriver's own element rect is in the document's): x, y,
    /// width, height.
    pub fn rect(&self, element: &str) -> [f64; 4] {
        let v = self.js(
            "const r = arguments[0].getBoundingClientRect(); return [r.x, r.y, r.width, r.height];",
            json!([{ ELEMENT: element }]),
        );
        [0, 1, 2, 3].map(|i| v[i].as_f64().expect("a number"))
    }

    /// Input actions (W3C `actions` sources), then their release.
    pub fn actions(&self, sources: Value) {
        self.cmd("POST", "/actions", json!({ "actions": sources }));
        self.cmd("DELETE", "/actions", json!({}));
    }

    /// The mouse to `(x, y)` CSS pixels of the page, pressed and released there.
    pub fn click_at(&self, x: f64, y: f64) {
        self.actions(json!([{"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": [
                {"type": "pointerMove", "duration": 0, "origin": "viewport", "x": x.round() as i64, "y": y.round() as i64},
                {"type": "pointerDown", "button": 0},
                {"type": "pointerUp", "button": 0}]}]));
    }

    /// The mouse to `(x, y)` CSS pixels of the page.
    pub fn move_to(&self, x: f64, y: f64) {
        self.actions(
            json!([{"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": [{"type": "pointerMove", "duration": 0, "origin": "viewport",
                "x": x.round() as i64, "y": y.round() as i64}]}]),
        );
    }

    /// One wheel notch (`delta_y` < 0 zooms in) at `(x, y)` CSS pixels of the page.
    pub fn wheel_at(&self, x: f64, y: f64, delta_y: i64) {
        self.actions(json!([{"type": "wheel", "id": "wheel", "actions": [
            {"type": "scroll", "origin": "viewport", "x": x.round() as i64, "y": y.round() as i64,
             "deltaX": 0, "deltaY": delta_y, "duration": 0}]}]));
    }

    /// Presses and releases each key of `keys` (WebDriver's key codes: "\u{E014}" is the
    /// right arrow) in the focused element.
    pub fn keys(&self, keys: &str) {
        let mut actions = Vec::new();
        for k in keys.chars() {
            actions.push(json!({"type": "keyDown", "value": k.to_string()}));
            actions.push(json!({"type": "keyUp", "value": k.to_string()}));
        }
        self.actions(json!([{"type": "key", "id": "keyboard", "actions": actions}]));
    }

    /// The page as RGBA8, `width` x `height` device pixels.
    pub fn screenshot(&self) -> Screenshot {
        let v = self.cmd("GET", "/screenshot", json!({}));
        let png = decode_base64(v.as_str().expect("base64 PNG"));
        let decoder = png::Decoder::new(std::io::Cursor::new(png.clone()));
        let mut reader = decoder.read_info().expect("a PNG");
        let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
        let info = reader.next_frame(&mut buf).expect("a PNG frame");
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        let channels = match info.color_type {
            png::ColorType::Rgba => 4,
            png::ColorType::Rgb => 3,
            other => panic!("screenshot colour type {other:?}"),
        };
        let mut rgba = Vec::with_capacity(4 * (info.width * info.height) as usize);
        for p in buf[..info.buffer_size()].chunks(channels) {
            rgba.extend_from_slice(&[p[0], p[1], p[2], if channels == 4 { p[3] } else { 255 }]);
        }
        Screenshot {
            width: info.width,
            height: info.height,
            rgba,
            png,
        }
    }

    /// The browser's console messages since the last call (chromedriver's log endpoint).
    pub fn console(&self) -> Vec<Value> {
        let v = self.cmd("POST", "/se/log", json!({"type": "browser"}));
        v.as_array().cloned().unwrap_or_default()
    }

    /// The console's errors (level SEVERE) since the last call.
    pub fn console_errors(&self) -> Vec<String> {
        self.console()
            .into_iter()
            .filter(|m| m["level"] == "SEVERE")
            .map(|m| m["message"].as_str().unwrap_or_default().to_string())
            .collect()
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        if !self.session.is_empty() {
            let _ = http(
                self.port,
                "DELETE",
                &format!("{}/session/{}", self.base, self.session),
                None,
            );
        }
        // The driver's process group: chromedriver and the chromium it started.
        unsafe {
            libc::killpg(self.driver.id() as i32, libc::SIGKILL);
        }
        let _ = self.driver.wait();
        let _ = std::fs::remove_dir_all(&self.profile);
    }
}

/// A screenshot's pixels.
pub struct Screenshot {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    /// The PNG as the driver sent it.
    pub png: Vec<u8>,
}

impl Screenshot {
    /// The RGB at `(x, y)` CSS pixels (one device pixel each).
    pub fn at(&self, x: f64, y: f64) -> [u8; 3] {
        let (x, y) = (x.floor() as u32, y.floor() as u32);
        assert!(
            x < self.width && y < self.height,
            "({x}, {y}) outside the screenshot"
        );
        let o = 4 * (y * self.width + x) as usize;
        [self.rgba[o], self.rgba[o + 1], self.rgba[o + 2]]
    }
}

fn decode_base64(text: &str) -> Vec<u8> {
    let value = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let clean: Vec<u8> = text.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    for chunk in clean.chunks(4) {
        let digits: Vec<u32> = chunk
            .iter()
            .filter(|&&c| c != b'=')
            .map(|&c| value(c))
            .collect();
        let mut n = 0u32;
        for (i, d) in digits.iter().enumerate() {
            n |= d << (18 - 6 * i);
        }
        for i in 0..digits.len().saturating_sub(1) {
            out.push((n >> (16 - 8 * i)) as u8);
        }
    }
    out
}
