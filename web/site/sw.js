// Offline: the site's files (listed and versioned by build.sh) are cached
// on first visit and served from the cache afterwards; a new build has a new
// version, which replaces the old cache. The PDF module is not in the list
// (it is fetched only when a PDF is made, to keep the first visit small):
// it joins the cache the first time it is fetched.
const VERSION = "__VERSION__";
const FILES = __FILES__;
const CACHE = `whycode-${VERSION}`;

self.addEventListener("install", (event) => {
  event.waitUntil(caches.open(CACHE).then((cache) => cache.addAll(FILES)).then(() => self.skipWaiting()));
});

self.addEventListener("activate", (event) => {
  event.waitUntil(
    caches.keys()
      .then((keys) => Promise.all(keys.filter((k) => k.startsWith("whycode-") && k !== CACHE).map((k) => caches.delete(k))))
      .then(() => self.clients.claim()),
  );
});

self.addEventListener("fetch", (event) => {
  const url = new URL(event.request.url);
  if (event.request.method !== "GET" || url.origin !== self.location.origin) return;
  event.respondWith(
    caches.open(CACHE).then((cache) =>
      cache.match(event.request, { ignoreSearch: true }).then((hit) => hit || fetch(event.request).then((response) => {
        if (response.ok && url.pathname.includes("/pkg/")) cache.put(event.request, response.clone());
        return response;
      }))),
  );
});
