// The page's one instance of the WebAssembly module (mbi-web.js, the C API of web/api/api.h),
// shared by main.js and camera.js: one download, one compile, one heap.
import createMbi from './mbi-web.js';

export default await createMbi();
